//! Mandelbulber2 settings files (`.fract`) read as fathom scenes.
//!
//! The format: a `# Mandelbulber settings file` header, then sections (`[main_parameters]`,
//! `[fractal_1]` .. `[fractal_9]`, free-text `[description]`, animation tables `[frames]` and
//! `[keyframes]`), each setting one line `key value;`. Numbers use a decimal point or, from
//! some locales, a decimal comma (`-1,25`); vectors are space-separated; colours are hex.
//! Only settings that differ from Mandelbulber's defaults are written, so the defaults below
//! (from `mandelbulber2 --list`, version 2.20) fill the rest.
//!
//! Mapping, with Mandelbulber's conventions:
//! - **World.** Mandelbulber's z is up, fathom's y: positions and directions are turned by
//!   `(x, y, z) -> (x, z, -y)` and the fractal node by `Rotate(x, -90)`, so the fractal is
//!   evaluated in Mandelbulber's own coordinates.
//! - **Camera.** `camera`, `target`, `camera_top` give eye, target and up. Mandelbulber's
//!   `fov` is the image plane's height at distance 1 (three-point perspective), so fathom's
//!   vertical field of view is `2 atan(fov / 2)`. Its rays go through pixel corners, fathom's
//!   through pixel centres: the target is moved by half a pixel (left and up) so pixel `(i, j)`
//!   sees what Mandelbulber's pixel `(i, j)` sees.
//! - **Formulas.** `formula_1` 1 (fast Mandelbulb, power 8) and 2 (Mandelbulb), 7 (Menger
//!   sponge) and 8 (Mandelbox). Mandelbulber's Mandelbulb measures the polar angle from the
//!   xy plane (asin) where fathom's measures it from +z (acos), and adds `alpha_angle_offset`
//!   and `beta_angle_offset` before multiplying by the power: with fathom's offsets
//!   (`azimuth_offset = alpha`, `polar_offset = 90 (1 - p) / p - beta` degrees) the two maps
//!   are the same. `N` is the iteration count; the bailout is the formula's default unless
//!   `use_default_bailout` is false; `DE_factor` scales the estimate's safety factor.
//! - Everything else (lights, colours, effects, hybrid slots, animation) has no fathom
//!   equivalent here and is listed in the warnings, one line per section, with line numbers.

use super::SceneFileError;
use crate::Call;
use crate::camera::Camera;
use crate::fractals::Fractal;
use crate::limits;
use crate::scene::{Node, Scene};
use crate::transforms::Transform;
use glam::DVec3;
use std::collections::BTreeMap;
use std::path::Path;

/// A `.fract` file read as a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The scene the file was translated into.
    pub scene: Scene,
    /// Every setting or section that was not carried over, and why.
    pub warnings: Vec<String>,
    /// Mandelbulber's image size (`image_width` x `image_height`).
    pub image_size: (u32, u32),
}

/// One `key value;` line.
#[derive(Clone, Debug)]
struct Setting {
    value: String,
    line: usize,
    /// 1-based column of the value's first character.
    col: usize,
}

/// The sections of a file, settings by key.
#[derive(Debug, Default)]
struct Sections {
    main: BTreeMap<String, Setting>,
    fractal: [BTreeMap<String, Setting>; 9],
    /// Sections read but not used: (name, first line, lines in it).
    skipped: Vec<(String, usize, usize)>,
}

/// Which section a line belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Section {
    Main,
    Fractal(usize),
    Skipped,
}

/// The formulas fathom maps, by Mandelbulber's internal id.
const FORMULAS: &[(i64, &str)] = &[
    (1, "fast Mandelbulb"),
    (2, "Mandelbulb"),
    (7, "Menger sponge"),
    (8, "Mandelbox"),
];

/// Mandelbulber's default bailout per formula (`use_default_bailout`).
fn default_bailout(formula: i64) -> f64 {
    match formula {
        8 => 100.0,
        _ => 10.0,
    }
}

struct Reader<'a> {
    origin: &'a str,
}

impl Reader<'_> {
    fn err(&self, line: usize, col: usize, msg: String) -> SceneFileError {
        SceneFileError::Syntax {
            origin: self.origin.into(),
            line,
            col,
            msg,
        }
    }

    fn parse(&self, text: &str) -> Result<Sections, SceneFileError> {
        let mut s = Sections::default();
        let mut first = true;
        let mut section = Section::Skipped;
        // A byte-order mark (some Windows editors write one) is not part of the header.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let l = raw.trim_end_matches('\r');
            if first {
                if !l.trim_start().starts_with("# Mandelbulber settings file") {
                    return Err(self.err(
                        line,
                        1,
                        "not a Mandelbulber settings file: the first line should be \
                         `# Mandelbulber settings file`"
                            .into(),
                    ));
                }
                first = false;
                continue;
            }
            let t = l.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            if t.starts_with('[') {
                let name = t
                    .strip_prefix('[')
                    .and_then(|r| r.strip_suffix(']'))
                    .ok_or_else(|| {
                        self.err(line, 1, format!("expected `[section]`, found `{t}`"))
                    })?;
                section = match name {
                    "main_parameters" => Section::Main,
                    n => match n
                        .strip_prefix("fractal_")
                        .and_then(|k| k.parse::<usize>().ok())
                    {
                        Some(k @ 1..=9) => Section::Fractal(k - 1),
                        _ => {
                            s.skipped.push((name.to_string(), line, 0));
                            Section::Skipped
                        }
                    },
                };
                continue;
            }
            if section == Section::Skipped {
                match s.skipped.last_mut() {
                    Some(last) => last.2 += 1,
                    None => {
                        return Err(self.err(
                            line,
                            1,
                            "a setting before any section; expected `[main_parameters]`".into(),
                        ));
                    }
                }
                continue;
            }
            let indent = l.len() - l.trim_start().len();
            let key_len = t
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(t.len());
            if key_len == 0 {
                return Err(self.err(
                    line,
                    indent + 1,
                    format!("expected a setting `key value;`, found `{}`", clip(t)),
                ));
            }
            let key = &t[..key_len];
            let rest = &t[key_len..];
            let Some(body) = rest.strip_suffix(';') else {
                return Err(self.err(
                    line,
                    char_col(l, l.len()) + 1,
                    format!("expected `;` ending the setting `{key}`"),
                ));
            };
            if !(body.is_empty() || body.starts_with([' ', '\t'])) {
                return Err(self.err(
                    line,
                    char_col(l, indent + key_len) + 1,
                    format!("expected a space between the setting `{key}` and its value"),
                ));
            }
            // An empty value is legal (an unset file name); typed reads refuse it.
            let value_at = indent + key_len + (body.len() - body.trim_start().len()).max(1);
            let map = match section {
                Section::Main => &mut s.main,
                Section::Fractal(k) => &mut s.fractal[k],
                Section::Skipped => unreachable!(),
            };
            let setting = Setting {
                value: body.trim().to_string(),
                line,
                col: char_col(l, value_at) + 1,
            };
            if let Some(prev) = map.insert(key.to_string(), setting) {
                return Err(self.err(
                    line,
                    indent + 1,
                    format!(
                        "`{key}` is given twice in this section (first at line {})",
                        prev.line
                    ),
                ));
            }
        }
        if first {
            return Err(self.err(
                1,
                1,
                "the file is empty; expected `# Mandelbulber settings file`".into(),
            ));
        }
        Ok(s)
    }
}

/// Column (0-based, in characters) of byte offset `b` in `l`.
fn char_col(l: &str, b: usize) -> usize {
    l.get(..b).map_or(b, |p| p.chars().count())
}

fn clip(t: &str) -> String {
    let s: String = t.chars().take(40).collect();
    if s.len() < t.len() { s + "..." } else { s }
}

/// Typed access to the settings of one section, remembering which were used.
struct Keys<'a> {
    r: &'a Reader<'a>,
    map: &'a BTreeMap<String, Setting>,
    used: std::cell::RefCell<Vec<String>>,
}

impl<'a> Keys<'a> {
    fn new(r: &'a Reader<'a>, map: &'a BTreeMap<String, Setting>) -> Self {
        Keys {
            r,
            map,
            used: Default::default(),
        }
    }

    fn get(&self, key: &str) -> Option<&'a Setting> {
        let s = self.map.get(key)?;
        self.used.borrow_mut().push(key.to_string());
        Some(s)
    }

    fn numbers(&self, key: &str, n: usize) -> Result<Option<Vec<f64>>, SceneFileError> {
        let Some(s) = self.get(key) else {
            return Ok(None);
        };
        if s.value.is_empty() {
            return Err(self.r.err(
                s.line,
                s.col,
                format!("the setting `{key}` has no value; expected `{key} VALUE;`"),
            ));
        }
        let parts: Vec<&str> = s.value.split_whitespace().collect();
        let what = if n == 1 {
            "a number".to_string()
        } else {
            format!(
                "{} numbers separated by spaces",
                ["", "one", "two", "three"].get(n).unwrap_or(&"several")
            )
        };
        if parts.len() != n {
            return Err(self.r.err(
                s.line,
                s.col,
                format!("`{key}` expects {what}, found `{}`", clip(&s.value)),
            ));
        }
        let mut out = Vec::with_capacity(n);
        for p in parts {
            let v: f64 = p.replace(',', ".").parse().map_err(|_| {
                self.r.err(
                    s.line,
                    s.col,
                    format!("`{key}` expects {what}; `{}` is not a number", clip(p)),
                )
            })?;
            if !v.is_finite() {
                return Err(self.r.err(
                    s.line,
                    s.col,
                    format!("`{key}` = {p}: every number must be finite"),
                ));
            }
            out.push(v);
        }
        Ok(Some(out))
    }

    fn number(&self, key: &str, default: f64) -> Result<f64, SceneFileError> {
        Ok(self.numbers(key, 1)?.map_or(default, |v| v[0]))
    }

    /// A number that must lie in `lo..=hi` (Mandelbulber would accept it, fathom cannot).
    fn ranged(&self, key: &str, default: f64, lo: f64, hi: f64) -> Result<f64, SceneFileError> {
        let v = self.number(key, default)?;
        if !(lo..=hi).contains(&v) {
            let s = &self.map[key];
            return Err(self.r.err(
                s.line,
                s.col,
                format!("`{key}` = {v} is out of the range fathom supports, [{lo}, {hi}]"),
            ));
        }
        Ok(v)
    }

    fn vec3(&self, key: &str, default: [f64; 3]) -> Result<DVec3, SceneFileError> {
        Ok(DVec3::from_slice(
            &self.numbers(key, 3)?.unwrap_or(default.to_vec()),
        ))
    }

    fn int(&self, key: &str, default: i64, lo: i64, hi: i64) -> Result<i64, SceneFileError> {
        let v = self.number(key, default as f64)?;
        if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
            let s = &self.map[key];
            return Err(self.r.err(
                s.line,
                s.col,
                format!(
                    "`{key}` expects a whole number in [{lo}, {hi}], found `{}`",
                    s.value
                ),
            ));
        }
        Ok(v as i64)
    }

    fn bool(&self, key: &str, default: bool) -> Result<bool, SceneFileError> {
        let Some(s) = self.get(key) else {
            return Ok(default);
        };
        match s.value.as_str() {
            "true" | "1" => Ok(true),
            "false" | "0" => Ok(false),
            v => Err(self.r.err(
                s.line,
                s.col,
                format!("`{key}` expects `true` or `false`, found `{}`", clip(v)),
            )),
        }
    }

    /// The settings nobody read, as `key (line N)`.
    fn unused(&self) -> Vec<String> {
        let used = self.used.borrow();
        self.map
            .iter()
            .filter(|(k, _)| !used.contains(k))
            .map(|(k, s)| format!("{k} (line {})", s.line))
            .collect()
    }
}

/// Mandelbulber's z-up world to fathom's y-up one.
fn to_y_up(v: DVec3) -> DVec3 {
    DVec3::new(v.x, v.z, -v.y)
}

/// Parses `.fract` text. `origin` names the source in messages.
pub fn parse(text: &str, origin: &str) -> Result<Imported, SceneFileError> {
    if text.len() as u64 > limits::MAX_SCENE_FILE_BYTES {
        return Err(SceneFileError::TooLarge {
            origin: origin.into(),
            size: text.len() as u64,
        });
    }
    let r = Reader { origin };
    let sections = r.parse(text)?;
    let main = Keys::new(&r, &sections.main);
    let mut warnings = Vec::new();

    let formula_line = main.get("formula_1").map(|s| (s.line, s.col));
    let formula = main.int("formula_1", 2, 0, 100_000)?;
    let Some(&(_, formula_name)) = FORMULAS.iter().find(|(id, _)| *id == formula) else {
        let (line, col) = formula_line.unwrap_or((1, 1));
        return Err(r.err(
            line,
            col,
            format!(
                "formula_1 = {formula} is not supported by fathom; supported: {}",
                FORMULAS
                    .iter()
                    .map(|(id, n)| format!("{id} ({n})"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    };
    for k in 2..=9 {
        let f = main.int(&format!("formula_{k}"), 0, 0, 100_000)?;
        if f != 0 {
            warnings.push(format!(
                "{origin}: formula_{k} = {f}: hybrid formula slots are not supported; only \
                 formula_1 ({formula_name}) was imported, so the shape will differ"
            ));
        }
    }
    for (key, what) in [
        ("hybrid_fractal_enable", "hybrid fractals"),
        ("julia_mode", "Julia mode"),
        ("boolean_operators", "boolean operators between formulas"),
    ] {
        if main.bool(key, false)? {
            warnings.push(format!(
                "{origin}:{}: `{key}` is on: {what} are not supported; the shape will differ",
                sections.main[key].line
            ));
        }
    }
    // Written as a number or, by newer versions, a name.
    let perspective = main
        .get("perspective_type")
        .map_or("0", |s| s.value.as_str());
    if !matches!(perspective, "0" | "threePoint") {
        warnings.push(format!(
            "{origin}:{}: perspective_type = {perspective}: only three-point perspective (0) is \
             supported; imported as a pinhole camera",
            sections.main["perspective_type"].line
        ));
    }
    let iterations = main.int("N", 250, 1, 1000)? as f64;
    let bailout = if main.bool("use_default_bailout", true)? {
        default_bailout(formula)
    } else {
        main.number("bailout", 100.0)?
    };
    let de_factor = main.number("DE_factor", 1.0)?;
    // A value fathom changes is reported with its line, never changed silently.
    let clamp_noted = |key: &str, v: f64, lo: f64, hi: f64, warnings: &mut Vec<String>| {
        let c = v.clamp(lo, hi);
        if c != v {
            let line = main.map.get(key).map_or(0, |s| s.line);
            warnings.push(format!(
                "{origin}:{line}: `{key}` = {v} is outside the range fathom supports for \
                 {formula_name}, [{lo}, {hi}]; clamped to {c}"
            ));
        }
        c
    };
    let frac = Keys::new(&r, &sections.fractal[0]);
    let (shape, default_safety) = match formula {
        1 | 2 => {
            let p = if formula == 1 {
                8.0
            } else {
                frac.ranged("power", 9.0, 2.0, 32.0)?
            };
            let alpha = frac.number("alpha_angle_offset", 0.0)?;
            let beta = frac.number("beta_angle_offset", 0.0)?;
            // Mandelbulber: latitude' = p (latitude + beta); fathom: colatitude' = p (colatitude +
            // offset). Equal when p offset = 90 (1 - p) - p beta (mod 360).
            let period = 360.0 / p;
            let polar = (90.0 * (1.0 - p) / p - beta).rem_euclid(period);
            let polar = if polar > period / 2.0 {
                polar - period
            } else {
                polar
            };
            let c = Call::new(Fractal::Mandelbulb)
                .with("power", &[p])
                .with("iterations", &[iterations])
                .with(
                    "bailout",
                    &[clamp_noted("bailout", bailout, 1.0, 1e3, &mut warnings)],
                )
                .with("azimuth_offset", &[alpha.rem_euclid(360.0)])
                .with("polar_offset", &[polar]);
            (c, 0.8)
        }
        7 => (
            Call::new(Fractal::Menger)
                .with("iterations", &[iterations])
                .with("scale", &[3.0])
                .with("offset", &[1.0, 1.0, 1.0]),
            1.0,
        ),
        8 => {
            let limit = frac.ranged("mandelbox_folding_limit", 1.0, 0.0, 4.0)?;
            let value = frac.number("mandelbox_folding_value", 2.0)?;
            if (value - 2.0 * limit).abs() > 1e-9 {
                warnings.push(format!(
                    "{origin}: mandelbox_folding_value = {value} is not twice the folding limit; \
                     fathom's box fold reflects (value = 2 x limit = {})",
                    2.0 * limit
                ));
            }
            let c = Call::new(Fractal::Mandelbox)
                .with("scale", &[frac.ranged("mandelbox_scale", 2.0, -4.0, 4.0)?])
                .with("folding_limit", &[limit])
                .with(
                    "min_radius",
                    &[frac.ranged("mandelbox_folding_min_radius", 0.5, 0.0, 4.0)?],
                )
                .with(
                    "fixed_radius",
                    &[frac.ranged("mandelbox_folding_fixed_radius", 1.0, 0.01, 4.0)?],
                )
                .with("iterations", &[iterations])
                .with(
                    "bailout",
                    &[clamp_noted("bailout", bailout, 2.0, 1e6, &mut warnings)],
                );
            (c, 0.6)
        }
        _ => unreachable!("checked against FORMULAS"),
    };
    let mut shape = shape;
    if formula != 7 {
        // fathom's safety factor is [0.01, 1]: DE_factor scales the formula's default.
        let safety = default_safety * de_factor;
        let clamped = safety.clamp(0.01, 1.0);
        if clamped != safety {
            let line = main.map.get("DE_factor").map_or(0, |s| s.line);
            warnings.push(format!(
                "{origin}:{line}: `DE_factor` = {de_factor} makes the step safety factor \
                 {safety} ({default_safety} x DE_factor), outside the range fathom supports, \
                 [0.01, 1]; clamped to {clamped}"
            ));
        }
        shape.set("safety", &[clamped]).expect("clamped into range");
    }

    // Camera.
    let eye = main.vec3("camera", [3.0, -6.0, 2.0])?;
    let target = main.vec3("target", [0.0, 0.0, 0.0])?;
    let top = main.vec3("camera_top", [-0.1277753, 0.2555506, 0.958314])?;
    let fov_mb = main.number("fov", 1.0)?;
    let w = main.int("image_width", 800, 1, 65536)? as u32;
    let h = main.int("image_height", 600, 1, 65536)? as u32;
    let forward = (target - eye).normalize_or_zero();
    let right = forward.cross(top).normalize_or_zero();
    let up = right.cross(forward);
    let aspect = w as f64 / h as f64;
    // Pixel corners to pixel centres: move the view centre half a pixel left and up.
    let dir = forward - right * (0.5 * aspect * fov_mb / w as f64) + up * (0.5 * fov_mb / h as f64);
    let dist = (target - eye).length();
    let camera = Camera {
        eye: to_y_up(eye),
        target: to_y_up(eye + dir * dist),
        up: to_y_up(top),
        fov: (2.0 * (fov_mb / 2.0).atan()).to_degrees(),
    };
    camera.validate().map_err(|msg| {
        let (line, col) = main
            .map
            .get("camera")
            .or(main.map.get("fov"))
            .map_or((1, 1), |s| (s.line, s.col));
        r.err(line, col, msg.to_string())
    })?;
    let mut scene = Scene::new(
        Node::new(shape).op(Call::new(Transform::Rotate)
            .with("axis", &[1.0, 0.0, 0.0])
            .with("angle", &[-90.0])),
    );
    scene.camera = camera;
    scene.render.max_distance = main.number("view_distance_max", 50.0)?.clamp(1e-3, 1e12);
    // Redundant with camera and target: read so they are not reported as unsupported.
    for k in [
        "camera_rotation",
        "camera_distance_to_target",
        "use_default_bailout",
    ] {
        main.get(k);
    }
    if !main.used.borrow().iter().any(|k| k == "bailout") {
        main.get("bailout"); // superseded by the formula's default bailout
    }
    let unused = main.unused();
    if !unused.is_empty() {
        warnings.push(format!(
            "{origin}: [main_parameters]: {} settings have no fathom equivalent and were ignored: {}",
            unused.len(),
            unused.join(", ")
        ));
    }
    let unused = frac.unused();
    if !unused.is_empty() {
        warnings.push(format!(
            "{origin}: [fractal_1]: {} settings are not used by fathom's {formula_name}: {}",
            unused.len(),
            unused.join(", ")
        ));
    }
    for (k, map) in sections.fractal.iter().enumerate().skip(1) {
        if !map.is_empty() {
            let keys: Vec<String> = map
                .iter()
                .map(|(k, s)| format!("{k} (line {})", s.line))
                .collect();
            warnings.push(format!(
                "{origin}: [fractal_{}]: {} settings of an unused formula slot ignored: {}",
                k + 1,
                keys.len(),
                keys.join(", ")
            ));
        }
    }
    for (name, line, n) in &sections.skipped {
        warnings.push(format!(
            "{origin}:{line}: section [{name}] ({n} lines) is not imported (descriptions and \
             animations have no place in a fathom scene)"
        ));
    }
    scene.validate().map_err(|error| SceneFileError::Invalid {
        origin: origin.into(),
        error,
    })?;
    Ok(Imported {
        scene,
        warnings,
        image_size: (w, h),
    })
}

/// Reads and parses a `.fract` file (refusing oversized files before reading them).
pub fn load(path: &Path) -> Result<Imported, SceneFileError> {
    let text = super::read_text(path)?;
    parse(&text, &path.display().to_string())
}

/// Whether `path` names a Mandelbulber settings file (by extension).
pub fn is_fract(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("fract"))
}

#[cfg(test)]
mod tests;
