//! Errors of the live layer, naming the binding or address at fault.

use std::net::SocketAddr;
use thiserror::Error;

/// Why the modulator or an OSC sender could not start or send.
#[derive(Debug, Error)]
pub enum LiveError {
    /// A binding is not usable; `at` says where (`bindings[2].source`).
    #[error("{at}: {msg}")]
    Binding {
        /// Where in the scene the binding stands.
        at: String,
        /// What is wrong with it.
        msg: String,
    },
    /// The listener could not bind its address.
    #[error("cannot listen for OSC on {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: SocketAddr,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// A message could not be built (bad address, too large).
    #[error("cannot build the OSC message: {0}")]
    Encode(String),
    /// Sending failed.
    #[error("cannot send to {to}: {source}")]
    Send {
        /// The receiver.
        to: SocketAddr,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
}
