//! Grows a physarum preset and writes projections of its trail (max along z, and a slice) as
//! PNG, printing ms per step: for tuning presets by eye.
//!
//! cargo run --release -p fathom-volume --example physarum_explore -- tendrils 128 200 /tmp/t

use fathom_volume::physarum::{Simulation, presets};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let name = a.get(1).map_or("tendrils", |s| s.as_str());
    let n: u32 = a.get(2).map_or(128, |s| s.parse().unwrap());
    let steps: u32 = a.get(3).map_or(200, |s| s.parse().unwrap());
    let out = a.get(4).map_or("/tmp/phys", |s| s.as_str());
    let mut p = presets::find(name, [n; 3]).unwrap();
    for kv in a.iter().skip(5) {
        let (k, v) = kv.split_once('=').unwrap();
        let f: f32 = v.parse().unwrap();
        match k {
            "sa" => p.sensor_angle = f,
            "sd" => p.sensor_distance = f,
            "ta" => p.turn_angle = f,
            "ss" => p.step_size = f,
            "decay" => p.decay = f,
            "diff" => p.diffusion = f,
            "roll" => p.roll = f,
            "agents" => p.agents = f as u32,
            _ => panic!("unknown {k}"),
        }
    }
    let mut s = Simulation::new(p, [n; 3], 1, 8 << 30).unwrap();
    let t = Instant::now();
    let mut tt = [0f64; 4];
    for _ in 0..steps {
        let t = s.step();
        tt[0] += t.move_ms;
        tt[1] += t.deposit_ms;
        tt[2] += t.diffuse_ms;
        tt[3] += t.sort_ms;
    }
    println!(
        "sort {:.1} move {:.1} deposit {:.1} diffuse {:.1} ms/step",
        tt[3] / steps as f64,
        tt[0] / steps as f64,
        tt[1] / steps as f64,
        tt[2] / steps as f64
    );
    let ms = t.elapsed().as_secs_f64() * 1e3 / steps as f64;
    println!(
        "{name}: {ms:.1} ms/step, {:.0} agent-steps/s",
        s.params().agents as f64 / ms * 1e3
    );
    let d = s.density();
    let n = n as usize;
    let mut mip = vec![0f32; n * n];
    let mut slice = vec![0f32; n * n];
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let v = d.data()[x + n * (y + n * z)];
                mip[x + n * y] = mip[x + n * y].max(v);
                if z == n / 2 {
                    slice[x + n * y] = v;
                }
            }
        }
    }
    for (img, suffix) in [(mip, "mip"), (slice, "slice")] {
        let px: Vec<u8> = img
            .iter()
            .map(|v| (v.min(1.0).sqrt() * 255.0) as u8)
            .collect();
        image::save_buffer(
            format!("{out}-{name}-{suffix}.png"),
            &px,
            n as u32,
            n as u32,
            image::ColorType::L8,
        )
        .unwrap();
    }
}
