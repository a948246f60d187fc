//! Tests of the trackers against closed forms: a homogeneous slab's transmittance is
//! exp(-sigma_t d), whether measured by delta tracking (the fraction of free flights that get
//! through) or estimated by ratio tracking, with any majorant choice; and the majorant grid
//! changes no expectation on a heterogeneous grid.

use super::*;
use crate::grid::Grid;

/// A slab x in [0, thickness] (wide in y and z) of uniform density 1, with one voxel of
/// density 3 in a far corner: the global majorant is then 3x the slab's extinction, so the
/// trackers make null collisions, while the majorant grid's cells on the test rays are exact.
fn slab(thickness: f32) -> DensityGrid {
    let res = [16, 16, 16];
    let bbox = WorldBox::new(Vec3::new(0.0, -4.0, -4.0), Vec3::new(thickness, 4.0, 4.0)).unwrap();
    let mut g = Grid::from_data(res, vec![1.0; 16 * 16 * 16], bbox).unwrap();
    let i = g.index(15, 15, 15);
    g.data_mut()[i] = 3.0;
    g
}

fn params(majorant: Majorant, homogeneous_cells: bool, scale: f32) -> MediumParams {
    MediumParams {
        density_scale: scale,
        majorant,
        homogeneous_cells,
        ..MediumParams::default()
    }
}

const MODES: [(Majorant, bool); 4] = [
    (Majorant::Global, false),
    (Majorant::Grid { block: 4 }, false),
    (Majorant::Grid { block: 4 }, true),
    (Majorant::Grid { block: 1 }, true),
];

#[test]
fn homogeneous_slab_transmittance_is_beer_lambert() {
    for (thickness, scale) in [(0.5f32, 2.0f32), (1.0, 1.0), (0.25, 8.0)] {
        let g = slab(thickness);
        for (maj, hom) in MODES {
            let m = Medium::new(g.clone(), &params(maj, hom, scale)).unwrap();
            for cos in [1.0f32, 0.6] {
                let d = Vec3::new(cos, (1.0 - cos * cos).sqrt(), 0.0);
                let o = Vec3::new(-1.0, -1.0, 0.3);
                let (t0, t1) = m.bbox().intersect(o, d).unwrap();
                let want = (-scale * thickness / cos).exp() as f64;
                let n = 100_000;
                let mut c = TrackCounters::default();
                let mut through = 0u64;
                let mut ratio = 0f64;
                let mut ratio2 = 0f64;
                for i in 0..n {
                    let mut rng = Stream::new(11, i, 0);
                    if m.sample_flight(o, d, t0, t1, &mut rng, &mut c).is_none() {
                        through += 1;
                    }
                    let tr = m.transmittance(o, d, t0, t1, &mut rng, &mut c) as f64;
                    ratio += tr;
                    ratio2 += tr * tr;
                }
                let nf = n as f64;
                let p = through as f64 / nf;
                let se = (want * (1.0 - want) / nf).sqrt();
                assert!(
                    (p - want).abs() < 5.0 * se + 1e-4,
                    "delta tracking {maj:?} {hom}: {p} vs {want} (d = {thickness}, scale {scale}, cos {cos})"
                );
                let mean = ratio / nf;
                let var = (ratio2 / nf - mean * mean).max(0.0);
                let se = (var / nf).sqrt();
                assert!(
                    (mean - want).abs() < 5.0 * se + 1e-4,
                    "ratio tracking {maj:?} {hom}: {mean} vs {want} +- {se}"
                );
                if maj == Majorant::Global {
                    assert!(
                        c.null_collisions > 0,
                        "the global majorant should make null collisions"
                    );
                }
            }
        }
    }
}

/// On a heterogeneous grid the four majorant choices give the same mean transmittance and
/// the same mean free-flight distance.
#[test]
fn majorant_choice_changes_no_expectation() {
    let mut r = Stream::new(2, 2, 2);
    let res = [12, 12, 12];
    let data = (0..12 * 12 * 12)
        .map(|_| if r.f32() < 0.5 { 0.0 } else { r.f32() * 2.0 })
        .collect();
    let g = Grid::from_data(res, data, WorldBox::UNIT).unwrap();
    let o = Vec3::new(-0.5, 0.1, 0.2);
    let d = Vec3::new(1.0, 0.35, 0.5).normalize();
    let (t0, t1) = g.bbox.intersect(o, d).unwrap();
    let mut results = Vec::new();
    for (maj, hom) in MODES {
        let m = Medium::new(g.clone(), &params(maj, hom, 3.0)).unwrap();
        let mut c = TrackCounters::default();
        let n = 200_000u64;
        let (mut tr, mut tr2, mut dist, mut dist2) = (0f64, 0f64, 0f64, 0f64);
        for i in 0..n {
            let mut rng = Stream::new(3, i, 1);
            let t = m.transmittance(o, d, t0, t1, &mut rng, &mut c) as f64;
            tr += t;
            tr2 += t * t;
            let f = m
                .sample_flight(o, d, t0, t1, &mut rng, &mut c)
                .map_or(t1, |c| c.t) as f64;
            dist += f;
            dist2 += f * f;
        }
        let nf = n as f64;
        let se = |s: f64, s2: f64| ((s2 / nf - (s / nf).powi(2)).max(0.0) / nf).sqrt();
        results.push((tr / nf, se(tr, tr2), dist / nf, se(dist, dist2), c.lookups));
    }
    let (a, sa, b, sb, lookups_global) = results[0];
    for &(x, sx, y, sy, lookups) in &results[1..] {
        assert!(
            (x - a).abs() < 5.0 * (sx * sx + sa * sa).sqrt(),
            "transmittance {x} vs {a}"
        );
        assert!(
            (y - b).abs() < 5.0 * (sy * sy + sb * sb).sqrt(),
            "free-flight distance {y} vs {b}"
        );
        assert!(
            lookups < lookups_global,
            "the majorant grid should save lookups"
        );
    }
}

#[test]
fn bad_parameters_name_their_range() {
    let g = slab(1.0);
    let cases = [
        (
            MediumParams {
                density_scale: -1.0,
                ..MediumParams::default()
            },
            "density scale = -1",
        ),
        (
            MediumParams {
                density_scale: f32::NAN,
                ..MediumParams::default()
            },
            "density scale = NaN",
        ),
        (
            MediumParams {
                albedo: Vec3::new(0.5, 1.5, 0.5),
                ..MediumParams::default()
            },
            "albedo = 1.5 is out of range: [0, 1]",
        ),
        (
            MediumParams {
                g: 1.0,
                ..MediumParams::default()
            },
            "g = 1",
        ),
        (
            MediumParams {
                majorant: Majorant::Grid { block: 0 },
                ..MediumParams::default()
            },
            "majorant block = 0",
        ),
        (
            MediumParams {
                emission: 1e9,
                ..MediumParams::default()
            },
            "emission = 1000000000",
        ),
    ];
    for (p, want) in cases {
        let e = Medium::new(g.clone(), &p).unwrap_err().to_string();
        assert!(e.contains(want), "expected `{want}` in: {e}");
    }
}
