//! Tests of the `.vol` reader and writer: exact round trips, Mitsuba's byte layout, clear
//! errors for every kind of bad file, a proptest fuzz over random and mutated bytes, and the
//! corpus in `vol-corpus/` replayed (each file's expected outcome is listed in its
//! `expect.txt`).

use super::*;
use proptest::prelude::*;
use std::path::PathBuf;

const LIMIT: u64 = 1 << 24;

fn grid(res: [u32; 3], data: Vec<f32>) -> DensityGrid {
    Grid::from_data(res, data, WorldBox::UNIT).unwrap()
}

#[test]
fn layout_matches_mitsuba() {
    // What `mi.VolumeGrid(np.arange(24).reshape(4, 3, 2, 1)).write(...)` writes (mitsuba 3.9):
    // x resolution 2, y 3, z 4, unit bounding box, values 0..24 in order.
    let g = grid([2, 3, 4], (0..24).map(|v| v as f32).collect());
    let b = to_bytes(&g);
    assert_eq!(b.len(), 48 + 96);
    assert_eq!(&b[..4], b"VOL\x03");
    assert_eq!(
        &b[4..24],
        &[1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 4, 0, 0, 0, 1, 0, 0, 0]
    );
    assert_eq!(
        &b[24..48],
        &[0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0]
            .map(f32::to_le_bytes)
            .concat()[..]
    );
    assert_eq!(&b[48 + 4 * 7..48 + 4 * 8], &7.0f32.to_le_bytes());
}

#[test]
fn file_round_trip_is_exact_and_keeps_the_box() {
    let mut g = grid([3, 1, 2], vec![0.0, 1e-38, 0.5, 3.25, 1e30, 7.0]);
    g.bbox = WorldBox::new(glam::Vec3::splat(-1.0), glam::Vec3::splat(2.0)).unwrap();
    let dir = std::env::temp_dir().join(format!("fathom-vol-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("g.vol");
    write(&p, &g).unwrap();
    let back = read(&p, LIMIT).unwrap();
    assert_eq!(back.grid.data(), g.data());
    assert_eq!(back.grid.res(), g.res());
    assert_eq!(
        back.grid.bbox,
        WorldBox::UNIT,
        "a read grid spans the unit cube, like Mitsuba's"
    );
    assert_eq!(back.file_box().unwrap(), g.bbox);
    assert_eq!(std::fs::read(&p).unwrap(), to_bytes(&g));
}

/// A valid file with the header fields overwritten.
fn patched(at: usize, bytes: &[u8]) -> Vec<u8> {
    let mut b = to_bytes(&grid([2, 2, 2], vec![1.0; 8]));
    b[at..at + bytes.len()].copy_from_slice(bytes);
    b
}

fn err(b: &[u8]) -> String {
    parse(b, Path::new("x.vol"), LIMIT).unwrap_err().to_string()
}

#[test]
fn bad_files_give_clear_errors() {
    let good = to_bytes(&grid([2, 2, 2], vec![1.0; 8]));
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (b"VOX\x03".to_vec(), "expected the bytes `VOL`"),
        (
            patched(3, &[2]),
            "version 2 is not supported (supported versions: 3)",
        ),
        (
            patched(4, &2i32.to_le_bytes()),
            "encoding 2 is not supported",
        ),
        (
            patched(8, &0i32.to_le_bytes()),
            "x resolution 0 is out of range 1..=8192",
        ),
        (patched(12, &(-5i32).to_le_bytes()), "y resolution -5"),
        (patched(20, &3i32.to_le_bytes()), "3 channels"),
        (
            patched(8, &[8192i32.to_le_bytes(); 3].concat()),
            "more than the memory limit",
        ),
        (
            good[..30].to_vec(),
            "truncated inside its header (expected the bounding box)",
        ),
        (
            good[..good.len() - 2].to_vec(),
            "truncated: it ends after 78 bytes, its header promises 80",
        ),
        (
            [good.clone(), vec![0; 3]].concat(),
            "3 unexpected bytes after the last voxel",
        ),
        (
            patched(48, &f32::NAN.to_le_bytes()),
            "voxel (0, 0, 0) holds NaN",
        ),
        (
            patched(52, &(-2.0f32).to_le_bytes()),
            "voxel (1, 0, 0) holds -2",
        ),
        (
            patched(76, &f32::INFINITY.to_le_bytes()),
            "voxel (1, 1, 1) holds inf",
        ),
        (
            vec![],
            "truncated inside its header (expected the magic bytes",
        ),
    ];
    for (bytes, want) in cases {
        let e = err(&bytes);
        assert!(e.contains(want), "expected `{want}` in: {e}");
        assert!(e.starts_with("x.vol: "), "{e}");
    }
}

#[test]
fn oversized_headers_are_refused_before_reading_the_voxels() {
    // A 48-byte file claiming 8192^3 voxels: refused by the limit, not by a failed allocation.
    let dir = std::env::temp_dir().join(format!("fathom-vol-big-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("big.vol");
    let mut b = patched(8, &8192i32.to_le_bytes());
    b[12..20].copy_from_slice(&[0, 32, 0, 0, 0, 32, 0, 0]);
    std::fs::write(&p, &b[..48]).unwrap();
    let e = read(&p, 4 << 30).unwrap_err().to_string();
    assert!(
        e.contains("8192x8192x8192") && e.contains("memory limit"),
        "{e}"
    );
    // Within the limit but the file is short: the length check comes before reading.
    b[8..20].copy_from_slice(&[0, 4, 0, 0, 0, 4, 0, 0, 0, 4, 0, 0]);
    std::fs::write(&p, &b[..48]).unwrap();
    let e = read(&p, 4 << 30).unwrap_err().to_string();
    assert!(e.contains("truncated"), "{e}");
}

/// Replays `vol-corpus/`: `expect.txt` lists `FILE ok` or `FILE error SUBSTRING`.
#[test]
fn corpus_replays() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("vol-corpus");
    let expect = std::fs::read_to_string(dir.join("expect.txt")).unwrap();
    let mut n = 0;
    for line in expect
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
    {
        let mut parts = line.splitn(3, ' ');
        let (file, outcome) = (parts.next().unwrap(), parts.next().unwrap());
        let got = read(&dir.join(file), LIMIT);
        match outcome {
            "ok" => {
                let v = got.unwrap_or_else(|e| panic!("{file}: {e}"));
                assert_eq!(
                    to_bytes(&{
                        let mut g = v.grid.clone();
                        g.bbox = v.file_box().unwrap();
                        g
                    }),
                    std::fs::read(dir.join(file)).unwrap(),
                    "{file} does not round-trip"
                );
            }
            "error" => {
                let want = parts.next().unwrap_or("");
                let e = got
                    .err()
                    .unwrap_or_else(|| panic!("{file} should fail"))
                    .to_string();
                assert!(e.contains(want), "{file}: expected `{want}` in: {e}");
            }
            o => panic!("expect.txt: unknown outcome {o}"),
        }
        n += 1;
    }
    assert!(n >= 8, "the corpus has only {n} entries");
}

fn arb_grid() -> impl Strategy<Value = DensityGrid> {
    (1u32..6, 1u32..6, 1u32..6).prop_flat_map(|(x, y, z)| {
        let n = (x * y * z) as usize;
        proptest::collection::vec(
            prop_oneof![
                Just(0.0f32),
                0.0f32..1e6,
                any::<u32>().prop_map(|b| f32::from_bits(b & 0x7f7f_ffff))
            ],
            n,
        )
        .prop_map(move |d| grid([x, y, z], d))
    })
}

proptest! {
    /// Any bytes: an error or a valid grid, never a panic.
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = parse(&bytes, Path::new("fuzz.vol"), LIMIT);
    }

    /// Byte flips, truncations and extensions of a valid file: an error, or a grid that writes
    /// back to the same bytes.
    #[test]
    fn mutated_files_fail_cleanly_or_round_trip(
        g in arb_grid(),
        flips in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..4),
        cut in proptest::option::of(any::<prop::sample::Index>()),
        extra in proptest::collection::vec(any::<u8>(), 0..3),
    ) {
        let mut b = to_bytes(&g);
        for (i, v) in flips {
            let i = i.index(b.len());
            b[i] = v;
        }
        if let Some(c) = cut {
            b.truncate(c.index(b.len() + 1));
        }
        b.extend(extra);
        if let Ok(v) = parse(&b, Path::new("fuzz.vol"), LIMIT) {
            v.grid.validate_densities("back").unwrap();
            let mut g2 = v.grid.clone();
            g2.bbox = WorldBox::UNIT;
            prop_assert_eq!(&to_bytes(&g2)[48..], &b[48..]);
        }
    }

    /// Every valid grid round-trips bit for bit.
    #[test]
    fn grids_round_trip_exactly(g in arb_grid()) {
        let v = parse(&to_bytes(&g), Path::new("rt.vol"), LIMIT).unwrap();
        prop_assert_eq!(v.grid, g);
    }
}
