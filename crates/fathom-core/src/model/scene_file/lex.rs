//! A light lexer over scene text, run before the RON parse: it refuses non-finite numbers
//! (`NaN`, `inf`, literals like `1e999` that overflow) with their position, since RON accepts
//! them and a NaN parameter would otherwise poison a render silently; and it finds top-level
//! fields (the format `version`) without a full parse.
//!
//! It recognises just enough of RON (comments, strings, identifiers, numbers, brackets) to not
//! mistake the inside of a comment or string for a number. It never fails on anything the RON
//! parser would report better (it passes unknown characters through as punctuation).

/// Kind of a token.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    Ident(String),
    Number(String),
    Str,
    Punct(char),
}

/// One token with its 1-based (line, column) and bracket depth (0 outside every bracket).
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    pub kind: Kind,
    pub pos: (usize, usize),
    pub depth: usize,
}

/// A lexing failure at a position.
#[derive(Debug)]
pub struct LexError {
    pub pos: (usize, usize),
    pub msg: String,
}

/// Names RON reads as non-finite floats.
const NON_FINITE: &[&str] = &["inf", "inff32", "inff64", "NaN", "NaNf32", "NaNf64"];

struct Cursor<'a> {
    chars: std::iter::Peekable<std::str::Chars<'a>>,
    line: usize,
    col: usize,
}

impl Cursor<'_> {
    fn peek(&mut self) -> Option<char> {
        self.chars.peek().copied()
    }
    fn bump(&mut self) -> Option<char> {
        let c = self.chars.next()?;
        if c == '\n' {
            self.line += 1;
            self.col = 1;
        } else {
            self.col += 1;
        }
        Some(c)
    }
    fn pos(&self) -> (usize, usize) {
        (self.line, self.col)
    }
}

/// Splits `text` into tokens, refusing non-finite numbers.
pub fn scan(text: &str) -> Result<Vec<Token>, LexError> {
    let mut c = Cursor {
        chars: text.chars().peekable(),
        line: 1,
        col: 1,
    };
    let mut out = Vec::new();
    let mut depth = 0usize;
    while let Some(ch) = c.peek() {
        let pos = c.pos();
        if ch.is_whitespace() {
            c.bump();
        } else if ch == '/' {
            c.bump();
            match c.peek() {
                Some('/') => {
                    while let Some(x) = c.bump() {
                        if x == '\n' {
                            break;
                        }
                    }
                }
                Some('*') => {
                    c.bump();
                    // RON block comments nest.
                    let mut level = 1usize;
                    let mut prev = '\0';
                    while level > 0 {
                        let Some(x) = c.bump() else { break };
                        if prev == '/' && x == '*' {
                            level += 1;
                            prev = '\0';
                        } else if prev == '*' && x == '/' {
                            level -= 1;
                            prev = '\0';
                        } else {
                            prev = x;
                        }
                    }
                }
                _ => out.push(Token {
                    kind: Kind::Punct('/'),
                    pos,
                    depth,
                }),
            }
        } else if ch == '"' {
            c.bump();
            let mut escaped = false;
            while let Some(x) = c.bump() {
                match (escaped, x) {
                    (true, _) => escaped = false,
                    (false, '\\') => escaped = true,
                    (false, '"') => break,
                    _ => {}
                }
            }
            out.push(Token {
                kind: Kind::Str,
                pos,
                depth,
            });
        } else if ch == '\'' {
            // A char literal: skip to the closing quote on the same line.
            c.bump();
            let mut escaped = false;
            while let Some(x) = c.peek() {
                if x == '\n' {
                    break;
                }
                c.bump();
                match (escaped, x) {
                    (true, _) => escaped = false,
                    (false, '\\') => escaped = true,
                    (false, '\'') => break,
                    _ => {}
                }
            }
            out.push(Token {
                kind: Kind::Str,
                pos,
                depth,
            });
        } else if ch.is_alphabetic() || ch == '_' {
            let mut s = String::new();
            while let Some(x) = c.peek() {
                if x.is_alphanumeric() || x == '_' || (x == '#' && s == "r") {
                    s.push(x);
                    c.bump();
                } else {
                    break;
                }
            }
            if NON_FINITE.contains(&s.as_str()) {
                return Err(LexError {
                    pos,
                    msg: format!(
                        "`{s}` is not allowed: every number in a scene file must be finite"
                    ),
                });
            }
            out.push(Token {
                kind: Kind::Ident(s),
                pos,
                depth,
            });
        } else if ch.is_ascii_digit() || ch == '.' {
            let mut s = String::new();
            let mut prev = '\0';
            while let Some(x) = c.peek() {
                let sign_in_exponent = (x == '+' || x == '-') && matches!(prev, 'e' | 'E');
                if x.is_ascii_alphanumeric() || x == '_' || x == '.' || sign_in_exponent {
                    s.push(x);
                    prev = x;
                    c.bump();
                } else {
                    break;
                }
            }
            check_number(&s, pos)?;
            out.push(Token {
                kind: Kind::Number(s),
                pos,
                depth,
            });
        } else {
            c.bump();
            match ch {
                '(' | '[' | '{' => {
                    out.push(Token {
                        kind: Kind::Punct(ch),
                        pos,
                        depth,
                    });
                    depth += 1;
                }
                ')' | ']' | '}' => {
                    depth = depth.saturating_sub(1);
                    out.push(Token {
                        kind: Kind::Punct(ch),
                        pos,
                        depth,
                    });
                }
                _ => out.push(Token {
                    kind: Kind::Punct(ch),
                    pos,
                    depth,
                }),
            }
        }
    }
    Ok(out)
}

/// Refuses a decimal literal that overflows to infinity (as f64, or as f32 with an `f32`
/// suffix), and hex, octal and binary literals (RON reads `0x0A` as `0` where a real number
/// is expected). Other malformed literals are left to the parser.
fn check_number(s: &str, pos: (usize, usize)) -> Result<(), LexError> {
    let clean: String = s.chars().filter(|&ch| ch != '_').collect();
    let (body, f32_suffix) = match clean.strip_suffix("f32") {
        Some(b) => (b, true),
        None => (clean.strip_suffix("f64").unwrap_or(&clean), false),
    };
    if ["0x", "0b", "0o", "0X", "0B", "0O"]
        .iter()
        .any(|p| body.starts_with(p))
    {
        return Err(LexError {
            pos,
            msg: format!("write numbers in decimal: `{s}` is not a decimal number"),
        });
    }
    let Ok(v) = body.parse::<f64>() else {
        return Ok(());
    };
    let finite = if f32_suffix {
        (v as f32).is_finite()
    } else {
        v.is_finite()
    };
    if finite {
        Ok(())
    } else {
        Err(LexError {
            pos,
            msg: format!(
                "the number `{s}` is too large to represent (it overflows to infinity); every \
                 number in a scene file must be finite"
            ),
        })
    }
}

/// The position and text of the number given to field `name` at the top level of the scene
/// (bracket depth 1), if it is written `name: <number>`.
pub fn top_level_number(tokens: &[Token], name: &str) -> Option<((usize, usize), String)> {
    tokens
        .windows(3)
        .find_map(|w| match (&w[0].kind, &w[1].kind, &w[2].kind) {
            (Kind::Ident(n), Kind::Punct(':'), Kind::Number(v)) if n == name && w[0].depth == 1 => {
                Some((w[2].pos, v.clone()))
            }
            _ => None,
        })
}

/// The 1-based (line, column) just after the end of `text`.
pub fn end_position(text: &str) -> (usize, usize) {
    let line = 1 + text.chars().filter(|&c| c == '\n').count();
    let col = 1 + text.chars().rev().take_while(|&c| c != '\n').count();
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_names_and_overflowing_literals_are_refused_with_position() {
        let e = scan("(a: 1.0,\n  b: NaN)").unwrap_err();
        assert_eq!(e.pos, (2, 6));
        assert!(e.msg.contains("finite"), "{}", e.msg);
        assert_eq!(scan("(x: -inf)").unwrap_err().pos, (1, 6));
        assert_eq!(scan("(x: 1e999)").unwrap_err().pos, (1, 5));
        assert_eq!(scan("(x: 1e39f32)").unwrap_err().pos, (1, 5));
        assert!(scan("(x: 1e38f32, y: 1e308, z: 1_000.5)").is_ok());
        assert!(scan("(x: 0x7f)").unwrap_err().msg.contains("decimal"));
    }

    #[test]
    fn comments_and_strings_are_skipped() {
        let t = scan("// NaN\n/* inf /* nested NaN */ 1e999 */ (\"NaN\", ok)").unwrap();
        let idents: Vec<_> = t
            .iter()
            .filter_map(|t| match &t.kind {
                Kind::Ident(s) => Some(s.as_str()),
                _ => None,
            })
            .collect();
        assert_eq!(idents, ["ok"]);
    }

    #[test]
    fn finds_the_top_level_version() {
        let t = scan("Scene(root: Node(version: 7), version: 3)").unwrap();
        assert_eq!(top_level_number(&t, "version"), Some(((1, 40), "3".into())));
    }
}

/// One step of a node path as `Scene::validate` writes it (`root.children[2].material`).
enum Seg<'a> {
    Field(&'a str),
    Index(usize),
}

/// Splits the path at the start of `msg` (up to the first character that cannot be part of a
/// path) into segments; `None` when the message does not start with a path.
fn path_segments(msg: &str) -> Option<Vec<Seg<'_>>> {
    let end = msg
        .find(|c: char| !(c.is_ascii_alphanumeric() || "_.[]".contains(c)))
        .unwrap_or(msg.len());
    let path = &msg[..end];
    let mut segs = Vec::new();
    for part in path.split('.') {
        let (name, rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if name.is_empty() || !name.starts_with(|c: char| c.is_ascii_lowercase()) {
            return None;
        }
        segs.push(Seg::Field(name));
        for idx in rest.split('[').skip(1) {
            segs.push(Seg::Index(idx.strip_suffix(']')?.parse().ok()?));
        }
    }
    (!segs.is_empty()).then_some(segs)
}

/// Steps into a value starting at token `k` at depth `d`: past a name and opening parentheses
/// (`Node(`, `Some((`), or one opening `[`. Returns the first token inside and its depth.
fn descend(tokens: &[Token], mut k: usize, mut d: usize) -> (usize, usize) {
    while let Some(t) = tokens.get(k) {
        match t.kind {
            Kind::Punct('(') => {
                d += 1;
                k += 1;
            }
            // A struct name or `Some`, not a field name inside the struct.
            Kind::Ident(_) if tokens.get(k + 1).map(|n| &n.kind) == Some(&Kind::Punct('(')) => {
                k += 1;
            }
            Kind::Punct('[') => return (k + 1, d + 1),
            _ => break,
        }
    }
    (k, d)
}

/// The position of the text a validation message's leading path names (`root.children[0]
/// .material: ...` points at that `material` field), as near as the text allows; `None` when
/// the message has no path or the scene is not a bracketed structure.
pub fn locate_path(tokens: &[Token], msg: &str) -> Option<(usize, usize)> {
    let segs = path_segments(msg)?;
    let open = tokens
        .iter()
        .position(|t| t.kind == Kind::Punct('(') && t.depth == 0)?;
    let (mut i, mut d) = (open + 1, 1);
    let mut pos = None;
    for seg in segs {
        match seg {
            Seg::Field(name) => {
                let mut j = i;
                loop {
                    let t = tokens.get(j)?;
                    if t.depth < d {
                        return pos; // not written out (a default): the nearest enclosing place
                    }
                    let is_field = t.depth == d
                        && t.kind == Kind::Ident(name.to_string())
                        && tokens.get(j + 1).map(|n| &n.kind) == Some(&Kind::Punct(':'));
                    if is_field {
                        break;
                    }
                    j += 1;
                }
                pos = Some(tokens[j].pos);
                (i, d) = descend(tokens, j + 2, d);
            }
            Seg::Index(n) => {
                let mut j = i;
                let mut seen = 0;
                while seen < n {
                    let t = tokens.get(j)?;
                    if t.depth < d {
                        return pos;
                    }
                    if t.depth == d && t.kind == Kind::Punct(',') {
                        seen += 1;
                    }
                    j += 1;
                }
                let t = tokens.get(j).filter(|t| t.depth >= d)?;
                pos = Some(t.pos);
                (i, d) = descend(tokens, j, d);
            }
        }
    }
    pos
}

#[cfg(test)]
mod locate_tests {
    use super::*;

    #[test]
    fn paths_resolve_to_their_fields() {
        let text = "Scene(version: 1,\n root: Node(shape: Sphere, children: [\n  Node(shape: Box),\n  Node(shape: Box, material: Material(specular: 3)),\n ]),\n ifs: Some((iterations: 2, ops: [FoldAbs, Rotate(angle: 1)])),\n camera: (fov: 0))";
        let t = scan(text).unwrap();
        assert_eq!(
            locate_path(&t, "root.children[1].material: bad"),
            Some((4, 20))
        );
        assert_eq!(locate_path(&t, "root.children[0]: bad"), Some((3, 3)));
        assert_eq!(locate_path(&t, "ifs.ops[1]: bad"), Some((6, 43)));
        assert_eq!(
            locate_path(&t, "camera.fov = 0 is out of range"),
            Some((7, 11))
        );
        // A default (not written) points at the nearest enclosing field.
        assert_eq!(
            locate_path(&t, "root.children[0].material: x"),
            Some((3, 3))
        );
        assert_eq!(locate_path(&t, "the tree is 40 levels deep"), None);
        assert_eq!(locate_path(&t, "9 lights; the limit is 8"), None);
    }
}
