//! Argument parsers shared by the subcommands: image sizes, 3-vectors and byte counts, each
//! with an error that shows what was expected.

use glam::DVec3;

/// Parses `WIDTHxHEIGHT` (each side 1..=16384).
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size `{s}` should look like 1280x720"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("size `{s}`: `{v}` is not a whole number"))
    };
    let (w, h) = (p(w)?, p(h)?);
    if w == 0 || h == 0 {
        return Err(format!("size {w}x{h} is empty"));
    }
    Ok((w, h))
}

/// Parses `x,y,z` (three finite numbers).
pub fn parse_vec(s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}` should be three numbers x,y,z"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(x, y, z)),
        _ => Err(format!("`{s}` should be three finite numbers x,y,z")),
    }
}

/// Parses a byte count with an optional K/M/G suffix (powers of 1024).
pub fn parse_bytes(s: &str) -> Result<usize, String> {
    let t = s.trim();
    let (num, mul) = match t.chars().last() {
        Some('k' | 'K') => (&t[..t.len() - 1], 1usize << 10),
        Some('m' | 'M') => (&t[..t.len() - 1], 1 << 20),
        Some('g' | 'G') => (&t[..t.len() - 1], 1 << 30),
        _ => (t, 1),
    };
    let v: f64 = num
        .parse()
        .map_err(|_| format!("memory `{s}` must be a number with an optional K, M or G suffix"))?;
    if !(v.is_finite() && v > 0.0) || v * mul as f64 > 1e15 {
        return Err(format!(
            "memory `{s}` is out of range (0, 1e15] bytes (e.g. 512M, 4G)"
        ));
    }
    Ok((v * mul as f64) as usize)
}

/// Most worker threads a command accepts.
pub const MAX_THREADS: usize = 1024;

/// The worker pool for `--threads` (default: all cores), refusing counts outside
/// [1, MAX_THREADS] with the range.
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    if let Some(t) = threads
        && !(1..=MAX_THREADS).contains(&t)
    {
        return Err(format!("--threads {t} is out of range [1, {MAX_THREADS}]"));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_vectors_and_bytes_parse_or_explain() {
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert!(parse_size("640").unwrap_err().contains("1280x720"));
        assert!(parse_size("ax4").is_err());
        assert!(parse_size("0x10").unwrap_err().contains("empty"));
        assert_eq!(parse_vec("1,-2,3.5"), Ok(DVec3::new(1.0, -2.0, 3.5)));
        assert!(parse_vec("1,2").is_err());
        assert!(parse_vec("1,2,nan").is_err());
        assert_eq!(parse_bytes("1G").unwrap(), 1 << 30);
        assert_eq!(parse_bytes("512M").unwrap(), 512 << 20);
        assert!(parse_bytes("lots").is_err());
        assert!(parse_bytes("-1").is_err());
        assert!(parse_bytes("0").unwrap_err().contains("(0, 1e15]"));
        for t in [0, 1025, 100_000] {
            let e = thread_pool(Some(t)).err().unwrap();
            assert!(e.contains("[1, 1024]"), "{e}");
        }
        assert_eq!(thread_pool(Some(2)).unwrap().current_num_threads(), 2);
    }
}
