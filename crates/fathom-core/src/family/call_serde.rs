//! How a registry call is written in a scene file: `Name(param: value, ...)`, or a bare `Name`
//! for entries without parameters. Parameters left out take their defaults; each value is
//! checked against its declared kind and range as it is read, so errors point at it.

use crate::call::Call;
use crate::registry::{Family, ParamKind};
use serde::de::{self, DeserializeSeed, EnumAccess, MapAccess, SeqAccess, VariantAccess, Visitor};
use serde::ser::{SerializeStructVariant, SerializeTuple};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::collections::HashMap;
use std::fmt;
use std::marker::PhantomData;
use std::sync::{LazyLock, Mutex};

/// Candidate names sorted nearest first (edit distance), for "did you mean" messages.
pub fn nearest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Vec<&'a str> {
    let lower = name.to_lowercase();
    let mut v: Vec<(usize, &str)> = candidates
        .into_iter()
        .map(|c| (strsim::levenshtein(&lower, &c.to_lowercase()), c))
        .collect();
    v.sort();
    v.into_iter().map(|(_, c)| c).collect()
}

/// "did you mean `a`? valid choices (nearest first): a, b, c" (or a note that there are none).
pub fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    let near = nearest(name, candidates);
    match near.first() {
        None => "there are no valid choices here".into(),
        Some(first) => format!(
            "did you mean `{first}`? valid choices (nearest first): {}",
            near.join(", ")
        ),
    }
}

/// "unknown X `name`; did you mean `a`? valid choices (nearest first): a, b, c"
pub fn unknown_name<'a>(
    noun: &str,
    name: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> String {
    format!(
        "unknown {noun} `{name}`; {}",
        did_you_mean(name, candidates)
    )
}

/// Static name lists per family, leaked once, for serde's `&'static [&'static str]` arguments.
fn names_of<K: Family>() -> &'static [&'static str] {
    static CACHE: LazyLock<Mutex<HashMap<&'static str, &'static [&'static str]>>> =
        LazyLock::new(|| Mutex::new(HashMap::new()));
    let mut c = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    c.entry(K::NOUN).or_insert_with(|| {
        Box::leak(
            K::all()
                .iter()
                .map(|k| k.def().name)
                .collect::<Vec<_>>()
                .into_boxed_slice(),
        )
    })
}

/// Static parameter-name lists per declaration, leaked once each.
fn param_names(def: &'static crate::registry::Def) -> &'static [&'static str] {
    static CACHE: LazyLock<Mutex<HashMap<usize, &'static [&'static str]>>> =
        LazyLock::new(|| Mutex::new(HashMap::new()));
    let mut c = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    c.entry(def as *const _ as usize).or_insert_with(|| {
        Box::leak(
            def.params
                .iter()
                .map(|p| p.name)
                .collect::<Vec<_>>()
                .into_boxed_slice(),
        )
    })
}

struct V3Ser<'a>(&'a [f64]);
impl Serialize for V3Ser<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(3)?;
        for x in self.0 {
            t.serialize_element(x)?;
        }
        t.end()
    }
}

impl<K: Family> Serialize for Call<K> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let def = self.kind.def();
        let idx = self.kind.index() as u32;
        if def.params.is_empty() {
            return s.serialize_unit_variant("Call", idx, def.name);
        }
        let mut sv = s.serialize_struct_variant("Call", idx, def.name, def.params.len())?;
        let mut off = 0;
        for p in def.params {
            let w = p.kind.width();
            let v = &self.params[off..off + w];
            match p.kind {
                ParamKind::Scalar => sv.serialize_field(p.name, &v[0])?,
                ParamKind::Int => sv.serialize_field(p.name, &(v[0] as i64))?,
                ParamKind::Vec3 => sv.serialize_field(p.name, &V3Ser(v))?,
            }
            off += w;
        }
        sv.end()
    }
}

impl<'de, K: Family> Deserialize<'de> for Call<K> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Call", names_of::<K>(), CallVisitor(PhantomData))
    }
}

/// How RON words `ExpectedStructLike` (a missing `(`); compared as text because the visitor
/// sees RON's error only through serde's generic error type.
const RON_EXPECTED_PAREN: &str = "Expected opening `(`";

struct CallVisitor<K>(PhantomData<K>);

impl<'de, K: Family> Visitor<'de> for CallVisitor<K> {
    type Value = Call<K>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "a {} such as `{}`", K::NOUN, K::all()[0].def().name)
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<Call<K>, A::Error> {
        let (Ident(name), variant) = data.variant()?;
        let kind = K::from_name(&name).ok_or_else(|| {
            de::Error::custom(unknown_name(
                K::NOUN,
                &name,
                K::all().iter().map(|k| k.def().name),
            ))
        })?;
        let def = kind.def();
        if def.params.is_empty() {
            variant.unit_variant()?;
            return Ok(Call::new(kind));
        }
        // A bare `Name` (no parentheses) for an entry with parameters takes all defaults. RON
        // reports the missing `(` as `ExpectedStructLike` before consuming anything, and no
        // error from inside the parameters can have that text (see `ParamSeed`), so the
        // parser is still just after the name and can carry on.
        match variant.struct_variant(param_names(def), ParamsVisitor { kind }) {
            Err(e) if e.to_string() == RON_EXPECTED_PAREN => Ok(Call::new(kind)),
            r => r,
        }
    }

    // `Name` written bare (no parentheses) for an entry with parameters: all defaults.
    fn visit_str<E: de::Error>(self, name: &str) -> Result<Call<K>, E> {
        K::from_name(name).map(Call::new).ok_or_else(|| {
            E::custom(unknown_name(
                K::NOUN,
                name,
                K::all().iter().map(|k| k.def().name),
            ))
        })
    }
}

/// An identifier (the entry name), read with `deserialize_identifier`.
struct Ident(String);

impl<'de> Deserialize<'de> for Ident {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Ident;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a name")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Ident, E> {
                Ok(Ident(v.to_string()))
            }
        }
        d.deserialize_identifier(V)
    }
}

struct ParamsVisitor<K> {
    kind: K,
}

impl<'de, K: Family> Visitor<'de> for ParamsVisitor<K> {
    type Value = Call<K>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let def = self.kind.def();
        write!(
            f,
            "the parameters of `{}` ({})",
            def.name,
            def.params
                .iter()
                .map(|p| p.name)
                .collect::<Vec<_>>()
                .join(", ")
        )
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Call<K>, A::Error> {
        let def = self.kind.def();
        let mut call = Call::new(self.kind);
        let mut seen = vec![false; def.params.len()];
        while let Some(key) = map.next_key::<String>()? {
            let Some(i) = def.params.iter().position(|p| p.name == key) else {
                return Err(de::Error::custom(format!(
                    "`{}` has no parameter `{key}`; {}",
                    def.name,
                    did_you_mean(&key, def.params.iter().map(|p| p.name))
                )));
            };
            if seen[i] {
                return Err(de::Error::custom(format!(
                    "parameter `{key}` of `{}` is given twice",
                    def.name
                )));
            }
            seen[i] = true;
            let spec = &def.params[i];
            let values = map.next_value_seed(ParamSeed {
                entry: def.name,
                spec,
            })?;
            let (off, _) = def.param(&key).expect("declared parameter");
            spec.check(&values)
                .map_err(|e| de::Error::custom(format!("{}: {e}", def.name)))?;
            call.params[off..off + values.len()].copy_from_slice(&values);
        }
        Ok(call)
    }
}

/// Reads one parameter value of the given kind: a number, or `(x, y, z)`. A value of the
/// wrong shape is reported naming the parameter and what it takes.
struct ParamSeed {
    entry: &'static str,
    spec: &'static crate::registry::ParamSpec,
}

impl<'de> DeserializeSeed<'de> for ParamSeed {
    type Value = Vec<f64>;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Vec<f64>, D::Error> {
        let r = match self.spec.kind {
            ParamKind::Scalar | ParamKind::Int => f64::deserialize(d).map(|x| vec![x]),
            ParamKind::Vec3 => d.deserialize_tuple(3, V3Visitor),
        };
        r.map_err(|e| {
            let text = e.to_string();
            let wrong_shape = text == RON_EXPECTED_PAREN
                || text == "Expected float"
                || text == "Expected integer"
                || (text.starts_with("Expected ") && text.ends_with(" instead"));
            if wrong_shape {
                let takes = match self.spec.kind {
                    ParamKind::Scalar => "a number",
                    ParamKind::Int => "a whole number",
                    ParamKind::Vec3 => "a vector `(x, y, z)` of three numbers",
                };
                de::Error::custom(format!(
                    "parameter `{}` of `{}` takes {takes}",
                    self.spec.name, self.entry
                ))
            } else {
                e
            }
        })
    }
}

struct V3Visitor;
impl<'de> Visitor<'de> for V3Visitor {
    type Value = Vec<f64>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a vector `(x, y, z)` of three numbers")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<f64>, A::Error> {
        let mut v = Vec::with_capacity(3);
        while let Some(x) = seq.next_element::<f64>()? {
            if v.len() == 3 {
                return Err(de::Error::custom("a vector has three components, got more"));
            }
            v.push(x);
        }
        if v.len() != 3 {
            return Err(de::Error::custom(format!(
                "a vector has three components, got {}",
                v.len()
            )));
        }
        Ok(v)
    }
}
