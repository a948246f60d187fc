//! The OSC listener: a thread that reads UDP datagrams, decodes them (`rosc`), matches each
//! message's address against the bindings' patterns and stores the latest level per binding in
//! an atomic slot. The frame loop reads the slots without locking, so a flood of packets never
//! blocks it; every packet is counted, and what cannot be used (not OSC, a NaN, a missing or
//! non-numeric argument) is counted as rejected and dropped.

use fathom_core::binding::OscInput;
use rosc::address::{Matcher, OscAddress};
use rosc::{OscPacket, OscType};
use serde::Serialize;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// How often the listener looks at its stop flag while no packets arrive.
const POLL: Duration = Duration::from_millis(20);
/// Deepest bundle nesting decoded; a datagram nested deeper is counted as malformed.
const MAX_BUNDLE_DEPTH: usize = 16;

/// What the listener has seen since it started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct OscCounters {
    /// UDP datagrams received.
    pub packets: u64,
    /// OSC messages in them (bundles unpacked).
    pub messages: u64,
    /// Values delivered to a binding.
    pub applied: u64,
    /// Packets and values that could not be used: `malformed + bad_values`.
    pub rejected: u64,
    /// Datagrams that are not OSC (or bundles nested too deeply, or invalid addresses).
    pub malformed: u64,
    /// Values that are NaN or infinite, not numbers, or missing (too few arguments).
    pub bad_values: u64,
    /// Values outside a binding's `from` range, clamped to it (and applied).
    pub clamped: u64,
    /// Messages whose address no binding listens to.
    pub unmatched: u64,
}

#[derive(Default)]
struct Counters {
    packets: AtomicU64,
    messages: AtomicU64,
    applied: AtomicU64,
    malformed: AtomicU64,
    bad_values: AtomicU64,
    clamped: AtomicU64,
    unmatched: AtomicU64,
}

impl Counters {
    fn snapshot(&self) -> OscCounters {
        let malformed = self.malformed.load(Relaxed);
        let bad_values = self.bad_values.load(Relaxed);
        OscCounters {
            packets: self.packets.load(Relaxed),
            messages: self.messages.load(Relaxed),
            applied: self.applied.load(Relaxed),
            rejected: malformed + bad_values,
            malformed,
            bad_values,
            clamped: self.clamped.load(Relaxed),
            unmatched: self.unmatched.load(Relaxed),
        }
    }
}

/// The latest level one binding received, and how many it has received.
#[derive(Default)]
pub(crate) struct LevelSlot {
    bits: AtomicU64,
    count: AtomicU64,
}

impl LevelSlot {
    /// The latest level and the number of values received (0: none yet).
    pub(crate) fn read(&self) -> (f64, u64) {
        // The count is written after the level: a non-zero count means a level is there.
        let count = self.count.load(std::sync::atomic::Ordering::Acquire);
        (f64::from_bits(self.bits.load(Relaxed)), count)
    }
    fn write(&self, level: f64) {
        self.bits.store(level.to_bits(), Relaxed);
        self.count
            .fetch_add(1, std::sync::atomic::Ordering::Release);
    }
}

/// One binding's OSC route.
pub(crate) struct Route {
    pub(crate) matcher: Matcher,
    pub(crate) input: OscInput,
    pub(crate) slot: Arc<LevelSlot>,
}

/// What the listener routes to; replaced as a whole when the bindings change.
#[derive(Default)]
pub(crate) struct Routes {
    pub(crate) routes: Vec<Route>,
}

/// State shared by the listener thread and the modulator.
#[derive(Default)]
pub(crate) struct Shared {
    counters: Counters,
    routes: Mutex<Arc<Routes>>,
}

impl Shared {
    pub(crate) fn counters(&self) -> OscCounters {
        self.counters.snapshot()
    }

    pub(crate) fn set_routes(&self, routes: Arc<Routes>) {
        *self.routes.lock().unwrap_or_else(|e| e.into_inner()) = routes;
    }

    fn routes(&self) -> Arc<Routes> {
        self.routes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    /// Decodes one datagram and routes its messages.
    pub(crate) fn handle(&self, bytes: &[u8]) {
        let c = &self.counters;
        c.packets.fetch_add(1, Relaxed);
        // rosc decodes nested bundles by recursion without a limit: a 64 KiB datagram of
        // bundles nested 3000 deep overflows the stack. Refuse deep nesting before decoding.
        if !nesting_within(bytes, MAX_BUNDLE_DEPTH) {
            c.malformed.fetch_add(1, Relaxed);
            return;
        }
        match rosc::decoder::decode_udp(bytes) {
            Ok((_, packet)) => {
                let routes = self.routes();
                self.visit(&routes, &packet);
            }
            Err(_) => {
                c.malformed.fetch_add(1, Relaxed);
            }
        }
    }

    fn visit(&self, routes: &Routes, packet: &OscPacket) {
        let c = &self.counters;
        match packet {
            OscPacket::Bundle(b) => {
                for p in &b.content {
                    self.visit(routes, p);
                }
            }
            OscPacket::Message(m) => {
                c.messages.fetch_add(1, Relaxed);
                let Ok(addr) = OscAddress::new(m.addr.clone()) else {
                    c.malformed.fetch_add(1, Relaxed);
                    return;
                };
                let mut matched = false;
                for r in routes
                    .routes
                    .iter()
                    .filter(|r| r.matcher.match_address(&addr))
                {
                    matched = true;
                    let level = m
                        .args
                        .get(r.input.arg)
                        .and_then(number)
                        .and_then(|x| r.input.level(x));
                    match level {
                        Some((level, clamped)) => {
                            if clamped {
                                c.clamped.fetch_add(1, Relaxed);
                            }
                            r.slot.write(level);
                            c.applied.fetch_add(1, Relaxed);
                        }
                        None => {
                            c.bad_values.fetch_add(1, Relaxed);
                        }
                    }
                }
                if !matched {
                    c.unmatched.fetch_add(1, Relaxed);
                }
            }
        }
    }
}

/// Whether the bundles in `bytes` nest at most `depth` deep (anything that is not a well-formed
/// bundle passes: the decoder refuses it without recursing).
fn nesting_within(bytes: &[u8], depth: usize) -> bool {
    if !bytes.starts_with(b"#bundle\0") || bytes.len() < 16 {
        return true;
    }
    if depth == 0 {
        return false;
    }
    let mut rest = &bytes[16..];
    while rest.len() >= 4 {
        let n = u32::from_be_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        rest = &rest[4..];
        if n > rest.len() {
            return true;
        }
        if !nesting_within(&rest[..n], depth - 1) {
            return false;
        }
        rest = &rest[n..];
    }
    true
}

/// The number an OSC argument carries, if it is one (booleans count as 0 and 1).
fn number(a: &OscType) -> Option<f64> {
    match a {
        OscType::Float(x) => Some(*x as f64),
        OscType::Double(x) => Some(*x),
        OscType::Int(x) => Some(*x as f64),
        OscType::Long(x) => Some(*x as f64),
        OscType::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
        _ => None,
    }
}

/// A running listener thread; stops and joins when dropped.
pub(crate) struct Listener {
    pub(crate) local: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Listener {
    /// Binds `addr` and starts the thread.
    pub(crate) fn start(addr: SocketAddr, shared: Arc<Shared>) -> std::io::Result<Listener> {
        let socket = UdpSocket::bind(addr)?;
        socket.set_read_timeout(Some(POLL))?;
        let local = socket.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let (s, halt) = (shared, stop.clone());
        let thread = std::thread::Builder::new()
            .name("fathom-osc".into())
            .spawn(move || {
                // The largest UDP payload: nothing is ever truncated silently.
                let mut buf = vec![0u8; 65536];
                while !halt.load(Relaxed) {
                    match socket.recv_from(&mut buf) {
                        Ok((n, _)) => s.handle(&buf[..n]),
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                            ) => {}
                        // ICMP errors and the like: nothing to do but go on listening.
                        Err(_) => std::thread::sleep(POLL),
                    }
                }
            })?;
        Ok(Listener {
            local,
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for Listener {
    fn drop(&mut self) {
        self.stop.store(true, Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
