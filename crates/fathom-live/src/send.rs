//! Sending OSC: what `fathom osc-send` and the tests and benchmarks use to drive a listener.

use crate::error::LiveError;
use rosc::{OscMessage, OscPacket, OscType};
use std::net::{SocketAddr, UdpSocket};

/// Encodes one message of float arguments (`f32`, as most OSC senders send). `nan` and
/// `inf` are sent as they are (to test a listener's rejection); a finite value too large for
/// an `f32` is refused rather than silently sent as infinity.
pub fn encode(address: &str, values: &[f64]) -> Result<Vec<u8>, LiveError> {
    rosc::address::verify_address(address)
        .map_err(|e| LiveError::Encode(format!("`{address}` is not an OSC address: {e}")))?;
    if let Some((i, v)) = values
        .iter()
        .enumerate()
        .find(|(_, v)| v.is_finite() && (**v as f32).is_infinite())
    {
        return Err(LiveError::Encode(format!(
            "value {} = {v:e} does not fit a 32-bit float (largest magnitude {:e}); send `inf` \
             to send an infinity",
            i + 1,
            f32::MAX
        )));
    }
    let msg = OscMessage {
        addr: address.into(),
        args: values.iter().map(|&v| OscType::Float(v as f32)).collect(),
    };
    rosc::encoder::encode(&OscPacket::Message(msg)).map_err(|e| LiveError::Encode(e.to_string()))
}

/// A UDP socket for sending OSC to one address.
pub struct Sender {
    socket: UdpSocket,
    to: SocketAddr,
}

impl Sender {
    /// A sender bound to an ephemeral local port on the same family as `to`.
    pub fn new(to: SocketAddr) -> Result<Sender, LiveError> {
        let local: SocketAddr = if to.is_ipv4() {
            "0.0.0.0:0".parse().expect("a literal address")
        } else {
            "[::]:0".parse().expect("a literal address")
        };
        let socket = UdpSocket::bind(local).map_err(|source| LiveError::Send { to, source })?;
        Ok(Sender { socket, to })
    }

    /// Sends raw bytes (an encoded packet, or garbage in tests).
    pub fn send_raw(&self, bytes: &[u8]) -> Result<(), LiveError> {
        self.socket
            .send_to(bytes, self.to)
            .map(|_| ())
            .map_err(|source| LiveError::Send {
                to: self.to,
                source,
            })
    }

    /// Sends one message of float arguments.
    pub fn send(&self, address: &str, values: &[f64]) -> Result<(), LiveError> {
        self.send_raw(&encode(address, values)?)
    }
}
