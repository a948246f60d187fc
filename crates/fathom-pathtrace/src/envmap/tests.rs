//! Tests of environment maps: reading, refusing bad files, sampling.

use super::*;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fathom-pathtrace-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn to_rgbe(c: [f32; 3]) -> [u8; 4] {
    let m = c[0].max(c[1]).max(c[2]);
    if m < 1e-32 {
        return [0; 4];
    }
    let e = m.log2().floor() as i32 + 1;
    let f = 256.0 / 2f32.powi(e);
    [
        (c[0] * f) as u8,
        (c[1] * f) as u8,
        (c[2] * f) as u8,
        (e + 128) as u8,
    ]
}

fn write_hdr(path: &Path, w: usize, h: usize, px: &[[f32; 3]], rle: bool) {
    let mut b = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
    for y in 0..h {
        let row: Vec<[u8; 4]> = (0..w).map(|x| to_rgbe(px[y * w + x])).collect();
        if rle {
            b.extend([2, 2, (w >> 8) as u8, (w & 255) as u8]);
            for c in 0..4 {
                // One literal run per channel (w <= 128 in the tests).
                b.push(w as u8);
                b.extend(row.iter().map(|p| p[c]));
            }
        } else {
            b.extend(row.iter().flatten());
        }
    }
    std::fs::write(path, b).unwrap();
}

fn gradient(w: usize, h: usize) -> Vec<[f32; 3]> {
    (0..w * h)
        .map(|i| [(i % w) as f32 * 0.5, (i / w) as f32, 0.25])
        .collect()
}

#[test]
fn rgbe_files_read_back_flat_and_run_length() {
    for rle in [false, true] {
        let p = tmp(&format!("g{rle}.hdr"));
        let (w, h) = (16, 8);
        let px = gradient(w, h);
        write_hdr(&p, w, h, &px, rle);
        let m = EnvMap::load(&p).unwrap();
        assert_eq!(m.size(), (w, h));
        for (i, want) in px.iter().enumerate() {
            let got = m.pixels[i];
            for c in 0..3 {
                // RGBE keeps 8 bits of mantissa per pixel.
                let tol = 0.01 * want[0].max(want[1]).max(want[2]) + 1e-6;
                assert!((got[c] - want[c]).abs() <= tol, "{i}: {got:?} vs {want:?}");
            }
        }
    }
}

#[test]
fn oversized_headers_are_refused_before_reading_pixels() {
    let p = tmp("huge.hdr");
    // A header claiming 200000 x 100000 pixels and no pixels at all: refused as too large
    // (not as truncated), i.e. before any pixel was read or allocated.
    std::fs::write(
        &p,
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 200000\n",
    )
    .unwrap();
    let e = EnvMap::load(&p).unwrap_err();
    assert!(matches!(
        e,
        EnvMapError::TooLarge {
            width: 200000,
            height: 100000,
            ..
        }
    ));
    assert!(e.to_string().contains("huge.hdr"), "{e}");
    // Within the side limit but over the pixel budget.
    std::fs::write(&p, "#?RADIANCE\n\n-Y 16000 +X 16000\n").unwrap();
    assert!(matches!(
        EnvMap::load(&p),
        Err(EnvMapError::TooLarge { .. })
    ));
}

#[test]
fn truncated_and_malformed_files_are_named() {
    let p = tmp("short.hdr");
    let (w, h) = (16, 8);
    write_hdr(&p, w, h, &gradient(w, h), true);
    let full = std::fs::read(&p).unwrap();
    std::fs::write(&p, &full[..full.len() - 40]).unwrap();
    let e = EnvMap::load(&p).unwrap_err();
    assert!(matches!(e, EnvMapError::Truncated { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("short.hdr") && msg.contains("scanline 7"),
        "{msg}"
    );
    std::fs::write(&p, &full[..20]).unwrap();
    assert!(matches!(
        EnvMap::load(&p),
        Err(EnvMapError::Truncated { .. })
    ));

    let q = tmp("bad.hdr");
    std::fs::write(&q, "P6\n1 1\n255\nabc").unwrap();
    let e = EnvMap::load(&q).unwrap_err();
    assert!(e.to_string().contains("bad.hdr") && e.to_string().contains("signature"));
    let missing = tmp("missing.hdr");
    let e = EnvMap::load(&missing).unwrap_err();
    assert!(matches!(e, EnvMapError::Io { .. }) && e.to_string().contains("missing.hdr"));
}

#[test]
fn exr_maps_read_and_truncated_exr_is_named() {
    let p = tmp("g.exr");
    let (w, h) = (16, 8);
    let px = gradient(w, h);
    let img = image::Rgb32FImage::from_fn(w as u32, h as u32, |x, y| {
        image::Rgb(px[(y as usize) * w + x as usize])
    });
    image::DynamicImage::ImageRgb32F(img).save(&p).unwrap();
    let m = EnvMap::load(&p).unwrap();
    assert_eq!(m.size(), (w, h));
    assert_eq!(m.pixels[3 * w + 5], px[3 * w + 5]);
    let full = std::fs::read(&p).unwrap();
    let t = tmp("cut.exr");
    std::fs::write(&t, &full[..full.len() / 2]).unwrap();
    let e = EnvMap::load(&t).unwrap_err();
    assert!(e.to_string().contains("cut.exr"), "{e}");
    assert!(
        matches!(
            e,
            EnvMapError::Truncated { .. } | EnvMapError::Malformed { .. }
        ),
        "{e:?}"
    );
}

#[test]
fn directions_and_uv_round_trip() {
    for d in [
        DVec3::new(0.3, 0.5, -0.8).normalize(),
        DVec3::new(-0.9, -0.1, 0.2).normalize(),
        DVec3::new(0.0, 0.2, 1.0).normalize(),
    ] {
        let back = uv_to_dir(dir_to_uv(d));
        assert!((back - d).length() < 1e-12, "{d} -> {back}");
    }
    // The map's centre looks down -z.
    assert!((uv_to_dir([0.5, 0.5]) - DVec3::NEG_Z).length() < 1e-12);
}

#[test]
fn sampling_finds_the_sun_and_its_density_is_consistent() {
    let (w, h) = (64, 32);
    let mut px = vec![[0.1f32; 3]; w * h];
    // A small bright patch.
    px[10 * w + 40] = [5000.0; 3];
    let m = EnvMap::from_pixels(w, h, px).unwrap();
    let sun = uv_to_dir([(40.5) / w as f64, 10.5 / h as f64]);
    let n = 4096;
    let mut near = 0;
    let mut integral = 0.0;
    for k in 0..n {
        let u = [
            crate::sampler::to_unit(crate::sampler::sobol0(k)),
            crate::sampler::to_unit(crate::sampler::sobol1(k)),
        ];
        let (d, l, pdf) = m.sample(u);
        if pdf == 0.0 {
            // Only at the pole itself (u = 0); the integrator skips such samples too.
            continue;
        }
        assert!(
            (pdf - m.pdf(d)).abs() <= 1e-9 * pdf.max(1.0),
            "{pdf} vs {}",
            m.pdf(d)
        );
        if d.dot(sun) > 0.99 {
            near += 1;
        }
        integral += crate::sampling::luminance(l) / pdf;
    }
    assert!(
        near as f64 > 0.8 * n as f64,
        "{near} of {n} samples near the sun"
    );
    // The estimate of int L dw matches the exact sum over pixels.
    let mut exact = 0.0;
    for y in 0..h {
        let t0 = std::f64::consts::PI * y as f64 / h as f64;
        let t1 = std::f64::consts::PI * (y + 1) as f64 / h as f64;
        let solid = 2.0 * std::f64::consts::PI / w as f64 * (t0.cos() - t1.cos());
        for x in 0..w {
            let p = m.pixels[y * w + x];
            exact += p[0] as f64 * solid;
        }
    }
    assert!(
        (integral / n as f64 / exact - 1.0).abs() < 0.02,
        "{} vs {exact}",
        integral / n as f64
    );
}
