//! Tests of the BSDF: sampling against its density (chi-square), reciprocity, energy.

use super::*;
use std::f64::consts::PI;

/// A small deterministic generator for the tests (xorshift64*).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn dir(theta: f64, phi: f64) -> DVec3 {
    DVec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

fn materials() -> Vec<(&'static str, PbrMaterial)> {
    vec![
        (
            "plastic",
            PbrMaterial {
                base_colour: [0.8, 0.3, 0.2],
                roughness: 0.5,
                specular: 0.5,
                ..PbrMaterial::diffuse([0.0; 3])
            },
        ),
        (
            "rough metal",
            PbrMaterial {
                base_colour: [0.95, 0.7, 0.3],
                metallic: 1.0,
                roughness: 0.8,
                ..PbrMaterial::diffuse([0.0; 3])
            },
        ),
        (
            "glossy metal",
            PbrMaterial {
                base_colour: [0.9, 0.9, 0.9],
                metallic: 1.0,
                roughness: 0.35,
                ..PbrMaterial::diffuse([0.0; 3])
            },
        ),
        (
            "half metal, tinted",
            PbrMaterial {
                base_colour: [0.2, 0.5, 0.9],
                metallic: 0.5,
                roughness: 0.6,
                specular: 1.0,
                specular_tint: 0.7,
                ..PbrMaterial::diffuse([0.0; 3])
            },
        ),
        ("lambert", PbrMaterial::diffuse([0.7, 0.7, 0.7])),
    ]
}

/// Wilson-Hilferty approximation of the chi-square quantile with `k` degrees of freedom at
/// standard-normal quantile `z`.
fn chi2_quantile(k: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// Draws directions from `sample` and compares the histogram over (theta, phi) bins with the
/// counts `pdf` predicts; the samples `sample` refuses fall in one extra bin.
#[test]
fn sampling_matches_the_density_chi_square() {
    const NT: usize = 12;
    const NP: usize = 24;
    const N: usize = 200_000;
    for (name, m) in materials() {
        let b = Bsdf::new(&m);
        for theta_o in [0.3f64, 1.0, 1.4] {
            let wo = dir(theta_o, 0.4);
            let mut counts = vec![0f64; NT * NP + 1];
            let mut rng = Rng(0x1234_5678_9abc_def1 ^ (theta_o * 1e6) as u64);
            for _ in 0..N {
                let s = b.sample(wo, rng.next(), [rng.next(), rng.next()]);
                match s {
                    Some(s) => {
                        assert!(!s.delta);
                        let t = s.wi.z.clamp(-1.0, 1.0).acos();
                        let p = s.wi.y.atan2(s.wi.x).rem_euclid(2.0 * PI);
                        let it = ((t / (0.5 * PI)) * NT as f64).min(NT as f64 - 1.0) as usize;
                        let ip = ((p / (2.0 * PI)) * NP as f64).min(NP as f64 - 1.0) as usize;
                        counts[it * NP + ip] += 1.0;
                    }
                    None => counts[NT * NP] += 1.0,
                }
            }
            // Expected counts: integrate the density over each bin (midpoint, 16x16 cells).
            let mut expected = vec![0f64; NT * NP + 1];
            let sub = 16;
            let dt = 0.5 * PI / NT as f64;
            let dp = 2.0 * PI / NP as f64;
            let mut total = 0.0;
            for it in 0..NT {
                for ip in 0..NP {
                    let mut s = 0.0;
                    for a in 0..sub {
                        for c in 0..sub {
                            let t = (it as f64 + (a as f64 + 0.5) / sub as f64) * dt;
                            let p = (ip as f64 + (c as f64 + 0.5) / sub as f64) * dp;
                            s += b.pdf(wo, dir(t, p)) * t.sin();
                        }
                    }
                    let e = s * dt * dp / (sub * sub) as f64;
                    expected[it * NP + ip] = e * N as f64;
                    total += e;
                }
            }
            expected[NT * NP] = (1.0 - total).max(0.0) * N as f64;
            // Pool bins expected to see fewer than 5 samples.
            let (mut chi2, mut dof, mut pool_o, mut pool_e) = (0.0, 0.0, 0.0, 0.0);
            for (o, e) in counts.iter().zip(&expected) {
                if *e < 5.0 {
                    pool_o += o;
                    pool_e += e;
                } else {
                    chi2 += (o - e) * (o - e) / e;
                    dof += 1.0;
                }
            }
            if pool_e >= 5.0 {
                chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                dof += 1.0;
            } else {
                assert!(
                    pool_o < 30.0,
                    "{name}: {pool_o} samples where none are expected"
                );
            }
            // Significance 1e-4 per case (z = 3.72): a wrong density fails by orders of
            // magnitude, a correct one rarely by chance.
            let limit = chi2_quantile(dof - 1.0, 3.72);
            assert!(
                chi2 < limit,
                "{name}, theta_o {theta_o}: chi2 {chi2:.1} > {limit:.1} ({dof} bins)"
            );
        }
    }
}

#[test]
fn evaluation_is_reciprocal() {
    let mut rng = Rng(99);
    for (name, m) in materials() {
        let b = Bsdf::new(&m);
        for _ in 0..200 {
            let wo = dir(rng.next() * 1.5, rng.next() * 2.0 * PI);
            let wi = dir(rng.next() * 1.5, rng.next() * 2.0 * PI);
            let a = b.eval(wo, wi);
            let c = b.eval(wi, wo);
            assert!(
                (a - c).abs().max_element() <= 1e-9 * a.abs().max_element().max(1e-9),
                "{name}: f(wo, wi) = {a} but f(wi, wo) = {c}"
            );
        }
    }
}

/// The directional albedo int f cos dwi, estimated from the sampling weights.
fn albedo(b: &Bsdf, wo: DVec3, n: usize) -> DVec3 {
    let mut rng = Rng(7);
    let mut s = DVec3::ZERO;
    for _ in 0..n {
        if let Some(x) = b.sample(wo, rng.next(), [rng.next(), rng.next()]) {
            s += x.weight;
        }
    }
    s / n as f64
}

#[test]
fn energy_never_exceeds_one_and_white_materials_keep_all_of_it() {
    for (name, m) in materials() {
        let b = Bsdf::new(&m);
        for theta_o in [0.05, 0.5, 1.0, 1.3, 1.5] {
            let a = albedo(&b, dir(theta_o, 0.0), 40_000);
            assert!(
                a.max_element() <= 1.01,
                "{name} at theta {theta_o}: albedo {a}"
            );
        }
    }
    // White metal and a white base under a dielectric coat reflect everything (within the
    // tables' accuracy) at every angle: energy compensation works.
    for (name, m) in [
        (
            "white rough metal",
            PbrMaterial {
                base_colour: [1.0; 3],
                metallic: 1.0,
                roughness: 1.0,
                ..PbrMaterial::diffuse([1.0; 3])
            },
        ),
        (
            "white plastic",
            PbrMaterial {
                base_colour: [1.0; 3],
                roughness: 0.7,
                specular: 1.0,
                ..PbrMaterial::diffuse([1.0; 3])
            },
        ),
    ] {
        let b = Bsdf::new(&m);
        for theta_o in [0.1, 0.7, 1.2, 1.45] {
            let a = albedo(&b, dir(theta_o, 0.3), 100_000);
            assert!(
                (a - DVec3::ONE).abs().max_element() < 0.015,
                "{name} at theta {theta_o}: albedo {a}"
            );
        }
        // Without the compensation the rough metal would lose a third of the light.
        let (e, _) = AlbedoTables::get().lookup(0.5, 1.0);
        assert!(e < 0.8);
    }
}

#[test]
fn glass_splits_by_fresnel_and_conserves_energy() {
    let m = PbrMaterial {
        transmission: 1.0,
        ior: 1.5,
        ..PbrMaterial::diffuse([1.0; 3])
    };
    let b = Bsdf::new(&m);
    let wo = dir(0.6, 1.0);
    let f = fresnel_dielectric(wo.z, 1.5);
    let n = 20_000;
    let mut rng = Rng(3);
    let mut reflected = 0;
    for _ in 0..n {
        let s = b.sample(wo, rng.next(), [rng.next(), rng.next()]).unwrap();
        assert!(s.delta && (s.weight - DVec3::ONE).length() < 1e-12);
        if s.transmitted {
            // Snell: sin_t = sin_i / eta.
            let si = (1.0 - wo.z * wo.z).sqrt();
            let st = (1.0 - s.wi.z * s.wi.z).sqrt();
            assert!((st - si / 1.5).abs() < 1e-9 && s.wi.z < 0.0);
        } else {
            reflected += 1;
        }
    }
    let got = reflected as f64 / n as f64;
    assert!((got - f).abs() < 0.01, "reflected {got}, Fresnel {f}");
    // Normal incidence: ((1 - 1.5) / (1 + 1.5))^2 = 4 %; from inside past the critical angle
    // everything reflects.
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-12);
    assert_eq!(fresnel_dielectric(0.5, 1.0 / 1.5), 1.0);
}
