//! Material libraries: found beside the OBJ (or by file name where the path was written for elsewhere),
//! and checked line by line before `tobj` reads them.

use std::path::{Path, PathBuf};

use super::check::{parse_numbers, statement};
use super::{error, read_text};
use crate::scene::material::{LoadError, MAX_COLOUR};
use crate::scene::unrendered::Unrendered;

/// Loads an MTL named by `mtllib`: beside the OBJ as written, else by file name beside the OBJ.
pub(super) fn load_mtl(
    dir: &Path,
    requested: &Path,
    warnings: &mut Vec<String>,
    files: &mut Vec<PathBuf>,
) -> Result<tobj::MTLLoadResult, LoadError> {
    let as_written = dir.join(requested);
    let by_name = requested.file_name().map(|name| dir.join(name));
    let path = if as_written.is_file() {
        as_written
    } else if let Some(found) = by_name.filter(|p| p.is_file()) {
        warnings.push(format!(
            "mtllib '{}' does not resolve from {}; using {} found by file name",
            requested.display(),
            dir.display(),
            found.display()
        ));
        found
    } else {
        // Its materials then count as undefined: grey, each with its own warning.
        warnings.push(format!(
            "material library '{}' not found (looked in {} and for its file name there)",
            requested.display(),
            dir.display()
        ));
        return Ok(Err(tobj::LoadError::OpenFileFailed));
    };
    let text = read_text(&path).map_err(|e| error(&path, None, format!("cannot read: {e}")))?;
    files.push(path.clone());
    let checked = check_mtl(&path, &text, warnings)?;
    // `check_mtl` rejects everything tobj would; a parse error here must still not pass for "no materials".
    let materials =
        tobj::load_mtl_buf(&mut checked.as_bytes()).map_err(|e| error(&path, None, format!("material parser: {e}")))?;
    Ok(Ok(materials))
}

/// Strips `# comments` and checks, with the line, every statement `tobj` would reject (it reports no line,
/// and its colour parser panics on fewer than three values): colours are 3 finite non-negative numbers,
/// `Ns`/`Ni`/`d` a number, `illum` a small integer, `newmtl` and the texture maps a name.
///
/// Statements that would change a material's look but are not rendered (mirrors, glass, textures) are said
/// in `warnings`, once per material (`super::unrendered`).
pub(super) fn check_mtl(path: &Path, text: &str, warnings: &mut Vec<String>) -> Result<String, LoadError> {
    let mut out = String::with_capacity(text.len());
    let mut unrendered = Unrendered::new();
    let file = path.display().to_string();
    for (index, raw) in text.lines().enumerate() {
        let Some(st) = statement(raw) else {
            out.push('\n');
            continue;
        };
        let (keyword, args, line) = (st.keyword, &st.args, st.normalised());
        let err = |message: String| error(path, Some(index + 1), message);
        match keyword {
            "Kd" | "Ke" | "Ka" | "Ks" => {
                let values =
                    parse_numbers(args).map_err(|bad| err(format!("'{keyword}' value '{bad}' is not a number")))?;
                if values.len() != 3 || values.iter().any(|v| !v.is_finite() || *v < 0.0) {
                    return Err(err(format!("'{keyword}' needs 3 finite non-negative numbers")));
                }
                if let Some(big) = values.iter().find(|&&v| v > MAX_COLOUR) {
                    return Err(err(format!(
                        "'{keyword}' {big} exceeds {MAX_COLOUR:e}: sums of light this bright (and the reference's \
                         variance, which squares it) overflow single-precision floats; scale the scene's units"
                    )));
                }
            }
            "Ns" | "Ni" | "d" if args.first().and_then(|a| a.parse::<f32>().ok()).is_none_or(|v| !v.is_finite()) => {
                return Err(err(format!("'{keyword}' needs a number")));
            }
            "illum" if args.first().and_then(|a| a.parse::<u8>().ok()).is_none() => {
                return Err(err("'illum' needs an illumination model number (0 to 10)".into()));
            }
            "newmtl" | "map_Ka" | "map_Kd" | "map_Ke" | "map_Ks" | "map_Bump" | "map_bump" | "map_Ns" | "map_ns"
            | "map_NS" | "bump" | "map_d"
                if args.is_empty() =>
            {
                let what = if keyword == "newmtl" { "a material name" } else { "a file name" };
                return Err(err(format!("'{keyword}' needs {what}")));
            }
            _ => {}
        }
        unrendered.statement(&file, keyword, args);
        out.push_str(&line);
        out.push('\n');
    }
    warnings.extend(unrendered.warnings(&file));
    Ok(out)
}
