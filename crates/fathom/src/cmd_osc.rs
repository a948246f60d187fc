//! `fathom osc-send` (send OSC messages, to try bindings or test a listener) and
//! `fathom osc-monitor` (listen as the explorer would and print what a scene's bindings
//! receive): the two ends of plugging an EEG or audio pipeline into fathom (docs/live.md).

use clap::Args;
use fathom_live::{DEFAULT_OSC_BIND, Modulator, Sender};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Send an OSC message of float arguments over UDP.
///
/// Examples:
///   fathom osc-send /fathom/light 0.8
///   fathom osc-send /muse/elements/alpha_absolute 0.4 0.5 0.45 0.38 --to 127.0.0.1:5000
///   fathom osc-send /fathom/light 0.2 --repeat 100 --interval-ms 50
///   fathom osc-send /fathom/light nan        (a listener counts it as rejected)
#[derive(Args, Debug)]
#[command(verbatim_doc_comment, allow_negative_numbers = true)]
pub struct OscSendArgs {
    /// OSC address, e.g. /fathom/light.
    pub address: String,
    /// Argument values (sent as 32-bit floats; `nan` and `inf` are sent as they are, finite
    /// values beyond the 32-bit range are refused). Options may follow them.
    pub values: Vec<f64>,
    /// Where to send: HOST:PORT (a name such as localhost is resolved, IPv4 first).
    #[arg(long, default_value = DEFAULT_OSC_BIND)]
    pub to: String,
    /// Send the message this many times, [1, 10000000].
    #[arg(long, default_value_t = 1)]
    pub repeat: u64,
    /// Pause between repeats, ms, [0, 3600000].
    #[arg(long, default_value_t = 0)]
    pub interval_ms: u64,
}

/// Longest pause between repeats (an hour).
pub const MAX_INTERVAL_MS: u64 = 3_600_000;

/// Resolves `HOST:PORT` (an address or a name), preferring IPv4 (the listener's default).
fn resolve(to: &str) -> Result<SocketAddr, String> {
    use std::net::ToSocketAddrs;
    let addrs: Vec<SocketAddr> = to
        .to_socket_addrs()
        .map_err(|e| format!("--to `{to}`: expected HOST:PORT, e.g. 127.0.0.1:9000 ({e})"))?
        .collect();
    addrs
        .iter()
        .find(|a| a.is_ipv4())
        .or(addrs.first())
        .copied()
        .ok_or_else(|| format!("--to `{to}`: the name has no address"))
}

pub fn send(a: OscSendArgs) -> Result<(), String> {
    if !(1..=10_000_000).contains(&a.repeat) {
        return Err(format!(
            "--repeat {} is out of range [1, 10000000]",
            a.repeat
        ));
    }
    if a.interval_ms > MAX_INTERVAL_MS {
        return Err(format!(
            "--interval-ms {} is out of range [0, {MAX_INTERVAL_MS}] (an hour)",
            a.interval_ms
        ));
    }
    let tx = Sender::new(resolve(&a.to)?).map_err(|e| e.to_string())?;
    let bytes = fathom_live::send::encode(&a.address, &a.values).map_err(|e| e.to_string())?;
    for i in 0..a.repeat {
        tx.send_raw(&bytes).map_err(|e| e.to_string())?;
        if a.interval_ms > 0 && i + 1 < a.repeat {
            std::thread::sleep(Duration::from_millis(a.interval_ms));
        }
    }
    Ok(())
}

/// Listen for OSC as the explorer does and print what a scene's bindings receive.
///
/// Prints, once a second, the packets received and rejected and the value of every binding.
/// The listener binds 127.0.0.1 (this machine only) unless --osc-bind says otherwise; binding
/// 0.0.0.0 lets anyone who can reach the port drive the scene (see docs/live.md).
///
/// Examples:
///   fathom osc-monitor docs/examples/mandelbulb-dive.ron
///   fathom osc-monitor my.ron --osc-bind 0.0.0.0:12345 --seconds 30
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct OscMonitorArgs {
    /// Scene file whose bindings to run.
    pub scene: PathBuf,
    /// Address to listen on: HOST:PORT (0.0.0.0 accepts packets from other machines).
    #[arg(long, default_value = DEFAULT_OSC_BIND)]
    pub osc_bind: SocketAddr,
    /// Stop after this many seconds (0: run until interrupted).
    #[arg(long, default_value_t = 0.0)]
    pub seconds: f64,
}

pub fn monitor(a: OscMonitorArgs) -> Result<(), String> {
    let mut scene = fathom_core::scene_file::load(&a.scene).map_err(|e| e.to_string())?;
    if scene.bindings.is_empty() {
        return Err(format!(
            "{} has no bindings to drive (see docs/live.md for the `bindings` field)",
            a.scene.display()
        ));
    }
    if !(a.seconds.is_finite() && a.seconds >= 0.0) {
        return Err(format!("--seconds {} must be >= 0", a.seconds));
    }
    let mut m = Modulator::new(&scene).map_err(|e| e.to_string())?;
    let addr = m.listen(a.osc_bind).map_err(|e| e.to_string())?;
    eprintln!("listening for OSC on {addr} (Ctrl-C to stop)");
    let start = Instant::now();
    let mut next = 1.0;
    loop {
        let t = start.elapsed().as_secs_f64();
        let applied = m.apply(&mut scene, t);
        if t >= next {
            next += 1.0;
            let c = applied.counters;
            let mut line = format!(
                "{t:5.0} s: {} packets, {} rejected ({} malformed, {} bad values), {} unmatched",
                c.packets, c.rejected, c.malformed, c.bad_values, c.unmatched
            );
            for (b, live) in scene.bindings.iter().zip(m.live()) {
                match live.value {
                    Some(v) => line += &format!(" | {} = {v:.4}", b.param),
                    None => line += &format!(" | {} (nothing yet)", b.param),
                }
            }
            println!("{line}");
        }
        if a.seconds > 0.0 && t >= a.seconds {
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::FromArgMatches;

    fn args(list: &[&str]) -> Result<OscSendArgs, String> {
        let cmd = OscSendArgs::augment_args(clap::Command::new("osc-send"));
        let m = cmd
            .try_get_matches_from(std::iter::once("osc-send").chain(list.iter().copied()))
            .map_err(|e| e.to_string())?;
        OscSendArgs::from_arg_matches(&m).map_err(|e| e.to_string())
    }

    #[test]
    fn the_help_examples_parse_with_options_after_the_values() {
        let a = args(&[
            "/muse/elements/alpha_absolute",
            "0.4",
            "0.5",
            "0.45",
            "0.38",
            "--to",
            "127.0.0.1:5000",
        ])
        .unwrap();
        assert_eq!(a.values, [0.4, 0.5, 0.45, 0.38]);
        assert_eq!(a.to, "127.0.0.1:5000");
        let a = args(&["/fathom/light", "-0.25", "nan", "--repeat", "3"]).unwrap();
        assert_eq!(a.values[0], -0.25);
        assert!(a.values[1].is_nan());
        assert_eq!(a.repeat, 3);
    }

    #[test]
    fn names_resolve_and_out_of_range_values_are_refused() {
        assert!(resolve("localhost:9000").unwrap().is_ipv4());
        assert!(resolve("nowhere").unwrap_err().contains("HOST:PORT"));
        let mut a = args(&["/x", "1", "--interval-ms", "18446744073709551615"]).unwrap();
        let e = send(a).unwrap_err();
        assert!(e.contains("[0, 3600000]"), "{e}");
        a = args(&["/x", "1e39", "--to", "127.0.0.1:9"]).unwrap();
        let e = send(a).unwrap_err();
        assert!(e.contains("does not fit a 32-bit float"), "{e}");
    }
}
