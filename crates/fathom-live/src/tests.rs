use super::*;
use fathom_core::binding::{Binding, Lfo, OscInput, Source, Wave};
use fathom_core::presets;
use fathom_core::scene::Scene;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

fn osc(param: &str, address: &str, from: (f64, f64), to: (f64, f64), smoothing: f64) -> Binding {
    Binding {
        param: param.into(),
        source: Source::Osc(OscInput {
            address: address.into(),
            arg: 0,
            from,
        }),
        to,
        smoothing,
    }
}

fn bulb_with(bindings: Vec<Binding>) -> Scene {
    let mut s = presets::load("mandelbulb").unwrap();
    s.bindings = bindings;
    s.validate_animation().unwrap();
    s
}

fn local() -> SocketAddr {
    "127.0.0.1:0".parse().unwrap()
}

/// Calls `apply` until `done` holds for the counters (UDP on loopback arrives in microseconds;
/// the bound only keeps a broken build from hanging).
fn apply_until(
    m: &mut Modulator,
    scene: &mut Scene,
    t: f64,
    done: impl Fn(&OscCounters) -> bool,
) -> Applied {
    let start = Instant::now();
    loop {
        let a = m.apply(scene, t);
        if done(&a.counters) {
            return a;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "packets never arrived: {:?}",
            a.counters
        );
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
fn osc_packets_change_the_bound_parameter_with_mapping_and_smoothing() {
    // /eeg/alpha in [0, 40] drives the power over [4, 12]; /audio/level in [0, 1] drives the
    // light's intensity over [0.2, 1.2] with a 1 s time constant.
    let mut scene = bulb_with(vec![
        osc(
            "root.shape.power",
            "/eeg/alpha",
            (0.0, 40.0),
            (4.0, 12.0),
            0.0,
        ),
        osc(
            "lights[0].intensity",
            "/audio/*",
            (0.0, 1.0),
            (0.2, 1.2),
            1.0,
        ),
    ]);
    let power_before = scene.root.shape.params[0];
    let mut m = Modulator::new(&scene).unwrap();
    let addr = m.listen(local()).unwrap();
    assert!(addr.ip().is_loopback());
    // Nothing received yet: nothing is written.
    let a = m.apply(&mut scene, 0.0);
    assert!(a.edits.is_empty() && !a.changed);
    assert_eq!(scene.root.shape.params[0], power_before);

    let tx = Sender::new(addr).unwrap();
    tx.send("/eeg/alpha", &[30.0]).unwrap();
    tx.send("/audio/level", &[1.0]).unwrap();
    let a = apply_until(&mut m, &mut scene, 0.0, |c| c.applied == 2);
    // 30 of [0, 40] is 3/4 of the way: 4 + 0.75 * 8 = 10.
    assert_eq!(scene.root.shape.params[0], 10.0);
    assert!(a.changed && !a.camera);
    // The first value of a smoothed binding is taken as it is...
    assert!((scene.lights[0].intensity - 1.2).abs() < 1e-12);
    tx.send("/audio/level", &[0.0]).unwrap();
    apply_until(&mut m, &mut scene, 0.0, |c| c.applied == 3);
    // ... later ones approach exponentially: after one time constant, 1 - 1/e of the way.
    m.apply(&mut scene, 1.0);
    let want = 1.2 + (0.2 - 1.2) * (1.0 - (-1.0f64).exp());
    assert!((scene.lights[0].intensity - want).abs() < 1e-9);
    m.apply(&mut scene, 20.0);
    assert!((scene.lights[0].intensity - 0.2).abs() < 1e-6);
    // Out of the input range: clamped (and counted), still applied.
    tx.send("/eeg/alpha", &[400.0]).unwrap();
    let a = apply_until(&mut m, &mut scene, 20.0, |c| c.clamped == 1);
    assert_eq!(scene.root.shape.params[0], 12.0);
    assert_eq!(a.counters.rejected, 0);
    let live = m.live();
    assert_eq!(live[0].received, 2);
    assert_eq!(live[0].level, Some(1.0));
    assert_eq!(live[0].value, Some(12.0));
}

#[test]
fn garbage_and_nan_are_counted_and_ignored() {
    let mut scene = bulb_with(vec![osc(
        "root.shape.power",
        "/p",
        (0.0, 1.0),
        (2.0, 10.0),
        0.0,
    )]);
    let mut m = Modulator::new(&scene).unwrap();
    let addr = m.listen(local()).unwrap();
    let tx = Sender::new(addr).unwrap();
    tx.send("/p", &[0.5]).unwrap();
    apply_until(&mut m, &mut scene, 0.0, |c| c.applied == 1);
    assert_eq!(scene.root.shape.params[0], 6.0);
    // Not OSC, truncated OSC, NaN, infinity, a string, no argument, an unknown address.
    let valid = send::encode("/p", &[0.25]).unwrap();
    tx.send_raw(b"hello, renderer").unwrap();
    tx.send_raw(&valid[..valid.len() - 3]).unwrap();
    tx.send_raw(&[0xff; 7]).unwrap();
    tx.send("/p", &[f64::NAN]).unwrap();
    tx.send("/p", &[f64::INFINITY]).unwrap();
    let text = rosc::encoder::encode(&rosc::OscPacket::Message(rosc::OscMessage {
        addr: "/p".into(),
        args: vec![rosc::OscType::String("loud".into())],
    }))
    .unwrap();
    tx.send_raw(&text).unwrap();
    tx.send("/p", &[]).unwrap();
    tx.send("/q", &[0.9]).unwrap();
    let a = apply_until(&mut m, &mut scene, 1.0, |c| c.packets == 9);
    let c = a.counters;
    assert_eq!(c.malformed, 3, "{c:?}");
    assert_eq!(c.bad_values, 4, "{c:?}");
    assert_eq!(c.rejected, 7, "{c:?}");
    assert_eq!(c.unmatched, 1, "{c:?}");
    assert_eq!(c.applied, 1, "{c:?}");
    // The parameter kept the last good value.
    assert_eq!(scene.root.shape.params[0], 6.0);
    assert!(!a.changed);
    scene.validate().unwrap();
}

#[test]
fn lfos_and_osc_edit_numbers_only_so_the_session_never_recompiles() {
    use fathom_render::{SceneChange, Session};
    let mut scene = bulb_with(vec![
        Binding {
            param: "root.shape.power".into(),
            source: Source::Lfo(Lfo {
                wave: Wave::Sine,
                rate: 0.5,
                phase: 0.0,
                depth: 1.0,
                seed: 0,
            }),
            to: (6.0, 10.0),
            smoothing: 0.0,
        },
        Binding {
            param: "root.shape.iterations".into(),
            source: Source::Lfo(Lfo {
                wave: Wave::Triangle,
                rate: 0.25,
                phase: 0.0,
                depth: 1.0,
                seed: 0,
            }),
            to: (4.0, 12.0),
            smoothing: 0.0,
        },
        osc(
            "root.material.albedo.r",
            "/colour",
            (0.0, 1.0),
            (0.0, 1.0),
            0.0,
        ),
    ]);
    let mut session = Session::new(scene.clone()).unwrap();
    let mut m = Modulator::new(&scene).unwrap();
    // LFO values at given times: power = 8 + 2 sin(pi t), iterations = round(8 + 4 tri(t / 4)).
    for (t, power, iterations) in [
        (0.0, 8.0, 8.0),
        (0.5, 10.0, 10.0),
        (1.0, 8.0, 12.0),
        (1.5, 6.0, 10.0),
    ] {
        let a = m.apply(&mut scene, t);
        assert!(a.changed || t == 0.0);
        assert!((scene.root.shape.params[0] - power).abs() < 1e-12, "t {t}");
        assert_eq!(scene.root.shape.params[1], iterations, "t {t}");
        let change = session.set_scene(scene.clone()).unwrap();
        assert!(
            matches!(change, SceneChange::Params | SceneChange::Unchanged),
            "t {t}: {change:?}"
        );
    }
    m.feed(&send::encode("/colour", &[0.25]).unwrap());
    m.apply(&mut scene, 2.0);
    assert_eq!(scene.root.material.albedo[0], 0.25);
    assert_eq!(
        session.set_scene(scene.clone()).unwrap(),
        SceneChange::Params
    );
}

#[test]
fn rebinding_keeps_the_listener_and_stale_bindings_are_skipped() {
    let mut scene = presets::load("model-tree").unwrap();
    scene.bindings = vec![
        osc(
            "root.children[2].material.specular",
            "/s",
            (0.0, 1.0),
            (0.0, 1.0),
            0.0,
        ),
        osc("camera.fov", "/fov", (0.0, 1.0), (30.0, 90.0), 0.0),
    ];
    let mut m = Modulator::new(&scene).unwrap();
    let addr = m.listen(local()).unwrap();
    let tx = Sender::new(addr).unwrap();
    tx.send("/fov", &[0.5]).unwrap();
    let a = apply_until(&mut m, &mut scene, 0.0, |c| c.applied == 1);
    assert!(a.camera);
    assert_eq!(scene.camera.fov, 60.0);
    // The tree loses the node the first binding drives: skipped and reported, no panic.
    tx.send("/s", &[0.5]).unwrap();
    apply_until(&mut m, &mut scene, 0.0, |c| c.applied == 2);
    scene.root.children.truncate(1);
    let a = m.apply(&mut scene, 0.1);
    assert_eq!(a.stale, [0]);
    // A new binding set on the same listener; an invalid one is refused and changes nothing.
    let mut bad = scene.clone();
    bad.bindings[0].param = "root.children[7].shape.radius".into();
    let e = m.rebind(&bad).unwrap_err().to_string();
    assert!(e.starts_with("bindings[0].param"), "{e}");
    scene.bindings.remove(0);
    m.rebind(&scene).unwrap();
    assert_eq!(m.osc_addr(), Some(addr));
    tx.send("/fov", &[1.0]).unwrap();
    apply_until(&mut m, &mut scene, 0.2, |c| c.applied == 3);
    assert_eq!(scene.camera.fov, 90.0);
}

#[test]
fn a_flood_of_a_hundred_thousand_packets_does_not_stall_the_frame_loop() {
    // Timing is measured by `fathom bench live`; this checks that the loop keeps running and
    // every packet that arrives is accounted for.
    let mut scene = bulb_with(vec![osc(
        "root.shape.power",
        "/p",
        (0.0, 1.0),
        (2.0, 10.0),
        0.0,
    )]);
    let mut m = Modulator::new(&scene).unwrap();
    let addr = m.listen(local()).unwrap();
    let flood = std::thread::spawn(move || {
        let tx = Sender::new(addr).unwrap();
        let good = send::encode("/p", &[0.5]).unwrap();
        let nan = send::encode("/p", &[f64::NAN]).unwrap();
        for i in 0..100_000u32 {
            let r = match i % 3 {
                0 => tx.send_raw(&good),
                1 => tx.send_raw(&nan),
                _ => tx.send_raw(&i.to_le_bytes()),
            };
            // A full socket buffer is a dropped packet, as on any network.
            let _ = r;
        }
    });
    let mut frames = 0u64;
    while !flood.is_finished() {
        m.apply(&mut scene, frames as f64 / 60.0);
        frames += 1;
    }
    flood.join().unwrap();
    // After the flood a last value still gets through.
    let tx = Sender::new(addr).unwrap();
    let start = Instant::now();
    while scene.root.shape.params[0] != 10.0 {
        tx.send("/p", &[1.0]).unwrap();
        std::thread::sleep(Duration::from_millis(2));
        m.apply(&mut scene, 1e6);
        assert!(start.elapsed() < Duration::from_secs(10));
    }
    let c = m.counters();
    assert!(frames > 0);
    assert!(c.packets > 1000, "{c:?}");
    assert_eq!(c.packets, c.messages + c.malformed, "{c:?}");
    assert_eq!(c.messages, c.applied + c.bad_values + c.unmatched, "{c:?}");
    assert!(
        c.rejected > 0 && c.bad_values > 0 && c.malformed > 0,
        "{c:?}"
    );
}

#[test]
fn random_and_deeply_nested_datagrams_never_panic() {
    let scene = bulb_with(vec![osc(
        "root.shape.power",
        "/p",
        (0.0, 1.0),
        (2.0, 10.0),
        0.0,
    )]);
    let m = Modulator::new(&scene).unwrap();
    // A bundle nested as deep as a datagram allows.
    let mut nested = Vec::new();
    for _ in 0..3000 {
        let mut b = b"#bundle\0".to_vec();
        b.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 1]);
        b.extend_from_slice(&(nested.len() as u32).to_be_bytes());
        b.extend_from_slice(&nested);
        if b.len() > 65_000 {
            break;
        }
        nested = b;
    }
    m.feed(&nested);
    assert_eq!(m.counters().malformed, 1);
    // Bundles nested within the limit are decoded.
    let inner = send::encode("/p", &[0.5]).unwrap();
    let mut ok = inner.clone();
    for _ in 0..3 {
        let mut b = b"#bundle\0".to_vec();
        b.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 1]);
        b.extend_from_slice(&(ok.len() as u32).to_be_bytes());
        b.extend_from_slice(&ok);
        ok = b;
    }
    m.feed(&ok);
    assert_eq!(m.counters().applied, 1);
    // Random bytes, and valid messages with random corruption.
    let valid = send::encode("/p", &[0.5, 0.25]).unwrap();
    let mut x = 0x1234_5678_9abc_def0u64;
    let mut rnd = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    for i in 0..20_000 {
        let len = (rnd() % 200) as usize;
        let mut d: Vec<u8> = if i % 2 == 0 {
            (0..len).map(|_| rnd() as u8).collect()
        } else {
            valid.clone()
        };
        if !d.is_empty() {
            let k = (rnd() as usize) % d.len();
            d[k] = rnd() as u8;
            d.truncate(d.len() - (rnd() as usize % 3).min(d.len()));
        }
        m.feed(&d);
    }
    let c = m.counters();
    assert_eq!(c.packets, 20_002);
    assert!(c.malformed > 0);
}
