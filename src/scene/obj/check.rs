//! The checking pass over an OBJ file before `tobj` reads it: every error with its line, and what real
//! files do that `tobj` does not expect fixed (see the module above).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::{IGNORED_STATEMENTS, UNNAMED_GROUP, error};
use crate::scene::material::LoadError;

/// A statement with comments stripped: its keyword, its arguments as written (inner spacing kept, for names
/// with spaces), and its words.
pub(super) struct Statement<'a> {
    pub(super) keyword: &'a str,
    pub(super) rest: &'a str,
    pub(super) args: Vec<&'a str>,
}

pub(super) fn statement(raw: &str) -> Option<Statement<'_>> {
    let line = raw.split('#').next().unwrap_or("").trim();
    let mut words = line.split_whitespace();
    let keyword = words.next()?;
    Some(Statement { keyword, rest: line[keyword.len()..].trim(), args: words.collect() })
}

impl Statement<'_> {
    /// The statement as `tobj` reads it: one space between keyword and arguments.
    pub(super) fn normalised(&self) -> String {
        if self.rest.is_empty() { self.keyword.to_owned() } else { format!("{} {}", self.keyword, self.rest) }
    }
}

pub(super) struct CheckedObj {
    /// The file with comments stripped and ignorable statements blanked; line numbers are preserved.
    pub(super) text: String,
    /// Material names used by `usemtl`, with the first line using each.
    pub(super) used_materials: Vec<(String, usize)>,
    /// Per group (by the name tobj gives it) and material (as `usemtl` names it, empty before any): what
    /// its faces give. tobj makes a model of each, and invents what a face does not give.
    pub(super) faces: BTreeMap<(String, String), FacesGive>,
}

/// What the faces of one group and material give: how many name normals and how many do not, the same for
/// texture coordinates, and the first line of a face without them.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct FacesGive {
    pub(super) normals: (usize, usize),
    pub(super) uvs: (usize, usize),
    pub(super) first_without_uvs: Option<usize>,
}

pub(super) fn check_obj(path: &Path, text: &str, warnings: &mut Vec<String>) -> Result<CheckedObj, LoadError> {
    let mut out = String::with_capacity(text.len());
    let mut used_materials: Vec<(String, usize)> = Vec::new();
    let mut counts = [0usize; 3]; // v, vt, vn seen so far
    let (mut group, mut material) = (String::from(UNNAMED_GROUP), String::new());
    let mut faces: BTreeMap<(String, String), FacesGive> = BTreeMap::new();
    let mut ignored = BTreeSet::new();
    let mut stray_dots: Vec<(usize, String)> = Vec::new();
    for (index, raw) in text.lines().enumerate() {
        let line_no = index + 1;
        let err = |message: String| error(path, Some(line_no), message);
        let Some(mut st) = statement(raw) else {
            out.push('\n');
            continue;
        };
        let mut line = st.normalised();
        let (keyword, args) = (st.keyword, &mut st.args);
        match keyword {
            "v" => {
                // x y z [w] or x y z r g b
                if !matches!(args.len(), 3 | 4 | 6) {
                    return Err(err(format!(
                        "'v' takes 3 coordinates (optionally w, or r g b), found {} values",
                        args.len()
                    )));
                }
                let values = parse_lenient(args, line_no, &mut stray_dots)
                    .map_err(|bad| err(format!("'v' has a value that is not a number: '{bad}'")))?;
                if let Some(bad) = values.iter().find(|x| !x.is_finite()) {
                    return Err(err(format!("vertex coordinate {bad} is not finite")));
                }
                if args.len() == 4 {
                    let w = values[3];
                    if w == 0.0 {
                        return Err(err("vertex weight w is 0".into()));
                    }
                    // tobj divides the coordinates by w.
                    if let Some(bad) = values[..3].iter().map(|x| x / w).find(|x| !x.is_finite()) {
                        return Err(err(format!("vertex coordinate divided by its weight w {w} is {bad}, not finite")));
                    }
                }
                // The numbers as read (a stray trailing '.' dropped), so tobj reads what was checked. Vertex
                // colours are not used here, and tobj fails on a face whose vertices are not all coloured:
                // of x y z r g b, keep the position only.
                let kept = if args.len() == 6 { &args[..3] } else { &args[..] };
                line = numbers_line("v", kept);
                counts[0] += 1;
            }
            "vt" | "vn" => {
                let values = parse_lenient(args, line_no, &mut stray_dots)
                    .map_err(|bad| err(format!("'{keyword}' has a value that is not a number: '{bad}'")))?;
                if let Some(bad) = values.iter().find(|x| !x.is_finite()) {
                    return Err(err(format!("'{keyword}' value {bad} is not finite")));
                }
                line = numbers_line(keyword, args);
                if keyword == "vt" {
                    if !(1..=3).contains(&values.len()) {
                        return Err(err(format!("'vt' takes 1 to 3 values (u [v [w]]), found {}", values.len())));
                    }
                    if values.len() == 1 {
                        line.push_str(" 0"); // v defaults to 0; tobj wants it
                    }
                } else if values.len() != 3 {
                    return Err(err(format!("'vn' takes 3 values, found {}", values.len())));
                }
                counts[if keyword == "vt" { 1 } else { 2 }] += 1;
            }
            "f" | "l" | "p" => {
                let least = match keyword {
                    "f" => 3,
                    "l" => 2,
                    _ => 1,
                };
                if args.len() < least {
                    let what = match keyword {
                        "f" => "a face",
                        "l" => "a line",
                        _ => "a point statement",
                    };
                    return Err(err(format!("{what} needs at least {least} vertices, found {}", args.len())));
                }
                for vertex in args.iter() {
                    check_face_vertex(vertex, &counts).map_err(|m| err(format!("face vertex '{vertex}': {m}")))?;
                }
                if keyword == "f" {
                    let names = |slot| args.iter().all(|v| v.split('/').nth(slot).is_some_and(|n| !n.is_empty()));
                    let give = faces.entry((group.clone(), material.clone())).or_default();
                    let count = |(with, without): &mut (usize, usize), named: bool| match named {
                        true => *with += 1,
                        false => *without += 1,
                    };
                    count(&mut give.normals, names(2));
                    count(&mut give.uvs, names(1));
                    if !names(1) {
                        give.first_without_uvs.get_or_insert(line_no);
                    }
                }
                if keyword != "f" {
                    // Checked, then dropped: lines and points have no area to light.
                    out.push('\n');
                    continue;
                }
            }
            "usemtl" => {
                // The whole rest of the line is the name, as tobj takes it.
                let name = st.rest;
                if name.is_empty() {
                    return Err(err("'usemtl' needs a material name".into()));
                }
                if !used_materials.iter().any(|(n, _)| n == name) {
                    used_materials.push((name.to_owned(), line_no));
                }
                material = name.to_owned();
            }
            "mtllib" => {
                if args.is_empty() {
                    return Err(err("'mtllib' needs a file name".into()));
                }
            }
            "o" | "g" => {
                // As tobj names its models: the rest of the line.
                group = if st.rest.is_empty() { UNNAMED_GROUP.to_owned() } else { st.rest.to_owned() };
            }
            "s" => {}
            other if IGNORED_STATEMENTS.contains(&other) => {
                ignored.insert(other.to_owned());
                out.push('\n');
                continue;
            }
            other => return Err(err(format!("unknown statement '{other}' (not an OBJ line)"))),
        }
        out.push_str(&line);
        out.push('\n');
    }
    warn_stray_dots(path, &stray_dots, warnings);
    if !ignored.is_empty() {
        warnings.push(format!(
            "{}: ignored statements this renderer does not use: {}",
            path.display(),
            ignored.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    Ok(CheckedObj { text: out, used_materials, faces })
}

pub(super) fn parse_numbers<'a>(args: &[&'a str]) -> Result<Vec<f32>, &'a str> {
    args.iter().map(|a| a.parse::<f32>().map_err(|_| *a)).collect()
}

/// A number as common OBJ loaders read it: as written, or, when a stray `.` follows it (`-0.2200.`, in
/// McGuire's `CornellBox-Sphere.obj`), without that dot. Anything else that is not a number (`1.2.3`,
/// `abc`, `1e`) is refused.
pub(super) fn lenient_number(word: &str) -> Option<(f32, Option<&str>)> {
    if let Ok(x) = word.parse::<f32>() {
        return Some((x, None));
    }
    let trimmed = word.strip_suffix('.')?;
    // Only a dot after a digit: `.` and `-.` are no numbers, `1e.` no exponent.
    if !trimmed.ends_with(|c: char| c.is_ascii_digit()) {
        return None;
    }
    trimmed.parse::<f32>().ok().map(|x| (x, Some(trimmed)))
}

/// [`parse_numbers`] with [`lenient_number`]: each word read without its stray dot is noted as
/// (line, word) in `fixed`, and replaced in `args` by what was read.
pub(super) fn parse_lenient<'a>(
    args: &mut [&'a str],
    line: usize,
    fixed: &mut Vec<(usize, String)>,
) -> Result<Vec<f32>, &'a str> {
    let mut values = Vec::with_capacity(args.len());
    for arg in args.iter_mut() {
        let (x, trimmed) = lenient_number(arg).ok_or(*arg)?;
        if let Some(trimmed) = trimmed {
            fixed.push((line, arg.to_string()));
            *arg = trimmed;
        }
        values.push(x);
    }
    Ok(values)
}

/// A statement of numbers, rebuilt: keyword, one space, the numbers as read.
pub(super) fn numbers_line(keyword: &str, args: &[&str]) -> String {
    std::iter::once(keyword).chain(args.iter().copied()).collect::<Vec<_>>().join(" ")
}

/// Numbers shown one warning each before the rest are counted.
pub(super) const STRAY_DOTS_SHOWN: usize = 5;

/// One warning per number read without its stray dot (`file:line: '-0.2200.' read as -0.2200`), the
/// first few, then how many more.
pub(super) fn warn_stray_dots(path: &Path, fixed: &[(usize, String)], warnings: &mut Vec<String>) {
    for (line, word) in fixed.iter().take(STRAY_DOTS_SHOWN) {
        let read = &word[..word.len() - 1];
        warnings.push(format!("{}:{line}: '{word}' read as {read}", path.display()));
    }
    if fixed.len() > STRAY_DOTS_SHOWN {
        warnings.push(format!(
            "{}: {} more numbers followed by a stray '.' read without it",
            path.display(),
            fixed.len() - STRAY_DOTS_SHOWN
        ));
    }
}

/// `v`, `v/vt`, `v//vn` or `v/vt/vn`: 1-based, or negative counting back from the last element defined.
pub(super) fn check_face_vertex(vertex: &str, counts: &[usize; 3]) -> Result<(), String> {
    let parts: Vec<&str> = vertex.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err("expected v, v/vt, v//vn or v/vt/vn".into());
    }
    for (slot, part) in parts.iter().enumerate() {
        if part.is_empty() {
            continue;
        }
        let index: i64 = part.parse().map_err(|_| format!("'{part}' is not an integer index"))?;
        let count = counts[slot] as u64;
        // unsigned_abs: -i64::MIN does not fit an i64.
        let valid = index != 0 && index.unsigned_abs() <= count;
        if !valid {
            let what = ["vertex", "texture coordinate", "normal"][slot];
            return Err(format!("{what} index {index} does not refer to one of the {count} defined so far"));
        }
    }
    Ok(())
}
