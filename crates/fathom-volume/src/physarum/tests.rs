//! Tests of the simulation: determinism across thread counts, deposits and their
//! conservation, the steering rule, orthonormal frames, parameter ranges.

use super::*;

fn small(agents: u32) -> Params {
    Params {
        agents,
        ..presets::find("tendrils", [32; 3]).unwrap()
    }
}

fn run(threads: usize, p: &Params, res: [u32; 3], steps: u32) -> (Vec<u32>, Vec<Agent>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut s = Simulation::new(p.clone(), res, 77, 1 << 30).unwrap();
        for _ in 0..steps {
            s.step();
        }
        (s.trail_counts().to_vec(), s.agents().to_vec())
    })
}

#[test]
fn same_seed_is_bit_identical_on_1_and_2_threads() {
    for name in ["tendrils", "sheets", "lattice", "cage"] {
        let p = Params {
            agents: 20_000,
            ..presets::find(name, [40, 32, 24]).unwrap()
        };
        let one = run(1, &p, [40, 32, 24], 15);
        let two = run(2, &p, [40, 32, 24], 15);
        assert!(one.0.iter().any(|&v| v > 0), "{name}: no trail");
        assert!(
            one.0 == two.0,
            "{name}: trail grids differ between 1 and 2 threads"
        );
        assert!(
            one.1 == two.1,
            "{name}: agents differ between 1 and 2 threads"
        );
        assert!(
            one == run(3, &p, [40, 32, 24], 15),
            "{name}: 3 threads differ"
        );
    }
}

#[test]
fn deposits_are_counted_and_diffusion_conserves_them_before_decay() {
    let p = Params {
        decay: 1.0,
        diffusion: 0.0,
        ..small(5000)
    };
    let mut s = Simulation::new(p.clone(), [32; 3], 1, 1 << 30).unwrap();
    s.step();
    let total: u64 = s.trail_counts().iter().map(|&v| v as u64).sum();
    assert_eq!(total, 5000 * p.deposit as u64);
    // With diffusion (wrap, no decay) the total shrinks only by truncation: < 1 per voxel.
    let p = Params {
        decay: 1.0,
        diffusion: 0.7,
        boundary: Boundary::Wrap,
        ..small(5000)
    };
    let mut s = Simulation::new(p.clone(), [32; 3], 1, 1 << 30).unwrap();
    s.step();
    let total: u64 = s.trail_counts().iter().map(|&v| v as u64).sum();
    let want = 5000 * p.deposit as u64;
    assert!(
        total <= want && want - total < 32 * 32 * 32,
        "{total} vs {want}"
    );
}

#[test]
fn frames_stay_orthonormal_and_agents_stay_inside() {
    for b in [Boundary::Wrap, Boundary::Walls] {
        let p = Params {
            boundary: b,
            step_size: 3.0,
            roll: 40.0,
            ..small(3000)
        };
        let mut s = Simulation::new(p, [24, 20, 16], 5, 1 << 30).unwrap();
        for _ in 0..30 {
            s.step();
        }
        for a in s.agents() {
            assert!((a.forward.length() - 1.0).abs() < 1e-4 && (a.up.length() - 1.0).abs() < 1e-4);
            assert!(a.forward.dot(a.up).abs() < 1e-4);
            assert!(
                a.pos.cmpge(Vec3::ZERO).all() && a.pos.cmplt(Vec3::new(24.0, 20.0, 16.0)).all(),
                "{b:?}: {:?}",
                a.pos
            );
        }
    }
}

/// An agent whose flanking sensor k reads the strongest trail turns toward that sensor's
/// direction by the turn angle; with nothing ahead it picks among the tied sensors at random.
#[test]
fn agents_turn_toward_the_strongest_sensor() {
    let res = [32u32; 3];
    let p = small(1);
    let steer = Steering {
        sensor_cos: 45f32.to_radians().cos(),
        sensor_sin: 45f32.to_radians().sin(),
        turn_cos: 30f32.to_radians().cos(),
        turn_sin: 30f32.to_radians().sin(),
        ring: RING.map(|a| (a.to_radians().cos(), a.to_radians().sin())),
        roll: Vec::new(),
    };
    for k in 0..3 {
        let mut a = Agent {
            pos: Vec3::splat(16.5),
            forward: Vec3::X,
            up: Vec3::Y,
            rng: Stream::new(1, 2, 3),
        };
        let right = Vec3::Z;
        let (c, s) = steer.ring[k];
        let ring = Vec3::Y * c + right * s;
        let sensor = a.pos + (Vec3::X * steer.sensor_cos + ring * steer.sensor_sin) * 6.0;
        let mut trail = vec![0u32; 32 * 32 * 32];
        trail[cell_of(sensor, res) as usize] = 100;
        move_agent(&mut a, &steer, 6.0, 1.0, Boundary::Wrap, res, &trail);
        let want = Vec3::X * steer.turn_cos + ring * steer.turn_sin;
        assert!(
            (a.forward - want).length() < 1e-5,
            "sensor {k}: forward {} want {want}",
            a.forward
        );
        assert!(a.forward.dot(a.up).abs() < 1e-5);
    }
    // All zero: every sensor ties; over many agents all four choices occur.
    let mut seen = [false; 4];
    for i in 0..200 {
        let mut a = Agent {
            pos: Vec3::splat(16.5),
            forward: Vec3::X,
            up: Vec3::Y,
            rng: Stream::new(9, i, 0),
        };
        move_agent(
            &mut a,
            &steer,
            6.0,
            1.0,
            Boundary::Wrap,
            res,
            &vec![0; 32 * 32 * 32],
        );
        let k = if a.forward.dot(Vec3::X) > 0.999 {
            0
        } else if a.forward.y > 0.4 {
            1
        } else if a.forward.z > 0.0 {
            2
        } else {
            3
        };
        seen[k] = true;
    }
    assert_eq!(
        seen, [true; 4],
        "ties are broken at random among all sensors"
    );
    let _ = p;
}

#[test]
fn bad_parameters_and_sizes_are_refused() {
    let cases = [
        (
            Params {
                agents: 0,
                ..small(1)
            },
            "agents = 0 is out of range: 1..=",
        ),
        (
            Params {
                sensor_angle: 200.0,
                ..small(1)
            },
            "sensor angle = 200",
        ),
        (
            Params {
                step_size: 0.0,
                ..small(1)
            },
            "step size = 0",
        ),
        (
            Params {
                decay: 1.5,
                ..small(1)
            },
            "decay = 1.5 is out of range: [0, 1]",
        ),
        (
            Params {
                diffusion: f32::NAN,
                ..small(1)
            },
            "diffusion = NaN",
        ),
        (
            Params {
                deposit: 60000,
                ..small(1 << 20)
            },
            "1..=2048 with 1048576 agents",
        ),
        (
            Params {
                spawn: Spawn::Ball(3.0),
                ..small(1)
            },
            "spawn radius = 3",
        ),
    ];
    for (p, want) in cases {
        let e = Simulation::new(p, [16; 3], 1, 1 << 30)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains(want), "expected `{want}` in: {e}");
    }
    let e = Simulation::new(small(10), [2048; 3], 1, 1 << 30)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("memory limit"), "{e}");
    let e = presets::find("tendril", [8; 3]).err().unwrap().to_string();
    assert!(
        e.contains("valid presets: tendrils, sheets, lattice, cage"),
        "{e}"
    );
}
