//! OBJ + MTL loading through `tobj`, behind a checking pass that gives every error its `file:line`.
//!
//! The checking pass also fixes what real files do and `tobj` does not expect: a UTF-8 byte order mark,
//! `# comments` after values, tabs or several spaces after a statement's keyword (it rewrites each statement
//! as keyword, one space, arguments), `vt u` without v, vertex colours on some vertices only (dropped: unused
//! here), statements `tobj` does not know (curves, `lod`, …; dropped with a warning), and an `mtllib` path
//! written relative to some other directory (looked for by file name next to the OBJ). Lines (`l`) and points
//! (`p`) are checked and dropped: `tobj` would make a triangle of a three-point line. A number followed by a
//! stray `.` (`-0.2200.`) is read without it, with a warning naming its line, as common OBJ loaders read it;
//! other words that are no number (`1.2.3`, `abc`, `1e`) are refused with their line.

use std::cell::RefCell;
use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::material::{Cutout, Group, Imported, LoadError, Material};
use super::texture::Texture;

mod check;
mod mtl;

use check::check_obj;
use mtl::load_mtl;

fn error(file: &Path, line: Option<usize>, message: impl fmt::Display) -> LoadError {
    LoadError { file: file.to_owned(), line, message: message.to_string() }
}

/// OBJ statements that are valid but carry nothing this renderer uses (free-form geometry, display hints).
/// tobj's name for the faces before any `g` or `o` (and for a bare one).
const UNNAMED_GROUP: &str = "unnamed_object";

const IGNORED_STATEMENTS: &[&str] = &[
    "vp",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "mg",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "maplib",
    "usemap",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "call",
    "csh",
];

pub fn load(path: &Path) -> Result<Imported, LoadError> {
    let text = read_text(path).map_err(|e| error(path, None, format!("cannot read mesh: {e}")))?;
    let mut warnings = Vec::new();
    let checked = check_obj(path, &text, &mut warnings)?;
    drop(text); // the checked copy is what tobj reads: one copy of a large file in memory, not two

    // A bare file name's parent is "": the current directory, said as `.` in messages.
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new(".")).to_owned();
    let mtl_error: RefCell<Option<LoadError>> = RefCell::new(None);
    let mtl_warnings = RefCell::new(Vec::new());
    let files = RefCell::new(vec![path.to_owned()]);
    let options =
        tobj::LoadOptions { triangulate: true, ignore_points: true, ignore_lines: true, ..Default::default() };
    let loaded = tobj::load_obj_buf(&mut checked.text.as_bytes(), &options, |mtllib| {
        match load_mtl(&dir, mtllib, &mut mtl_warnings.borrow_mut(), &mut files.borrow_mut()) {
            Ok(result) => result,
            Err(e) => {
                mtl_error.borrow_mut().get_or_insert(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    });
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    warnings.extend(mtl_warnings.into_inner());
    // The checking pass rejects everything tobj would; this is a guard, not an expected path.
    let (models, materials) = loaded.map_err(|e| error(path, None, format!("OBJ parser: {e}")))?;
    let tobj_materials = materials.unwrap_or_default();

    let mut textures = TextureFiles::default();
    let mtl_dirs: Vec<PathBuf> = files.borrow()[1..].iter().filter_map(|f| f.parent().map(Path::to_owned)).collect();
    let mut materials = Vec::with_capacity(tobj_materials.len() + 1);
    for m in &tobj_materials {
        let kd_map = match &m.diffuse_texture {
            Some(file) => textures.find(&m.name, file, TextureUse::Colour, &mtl_dirs, &mut warnings)?,
            None => None,
        };
        // tobj keeps `map_Ke` among the statements it does not know.
        let ke_map = match m.unknown_param.get("map_Ke") {
            Some(file) => textures.find(&m.name, file, TextureUse::Emission, &mtl_dirs, &mut warnings)?,
            None => None,
        };
        let mut cutout = match &m.dissolve_texture {
            Some(file) => textures.find(&m.name, file, TextureUse::Mask, &mtl_dirs, &mut warnings)?,
            None => None,
        }
        .map(|map| Cutout { map, threshold: Cutout::MTL_THRESHOLD });
        if cutout.is_some() && m.emissive.is_some_and(|ke| ke.iter().any(|&c| c > 0.0)) {
            warnings.push(format!("material '{}': an emitter is not cut out: its map_d is ignored", m.name));
            cutout = None;
        }
        // MTL multiplies `map_Kd` by `Kd` and `map_Ke` by `Ke`; without the factor, the texture alone.
        let unstated = if kd_map.is_some() { 1.0 } else { Material::DEFAULT_KD };
        let ke = m.emissive.map(Vec3::from).unwrap_or(if ke_map.is_some() { Vec3::ONE } else { Vec3::ZERO });
        if ke_map.is_some() && ke.max_element() <= 0.0 {
            warnings.push(format!("material '{}': its map_Ke is multiplied by Ke 0: it emits nothing", m.name));
        }
        materials.push(Material {
            kd_map,
            ke_map,
            cutout,
            ..Material::new(&m.name, m.diffuse.map(Vec3::from).unwrap_or(Vec3::splat(unstated)), ke)
        });
    }
    let defined: BTreeSet<String> = materials.iter().map(|m| m.name.clone()).collect();
    for (name, line) in &checked.used_materials {
        if !defined.contains(name) {
            warnings.push(format!(
                "{}:{line}: material '{name}' is not defined in any MTL file; using grey Kd {} and no emission",
                path.display(),
                Material::DEFAULT_KD
            ));
        }
    }
    let default_material = materials.len();
    materials.push(Material::new("(default grey)", Vec3::splat(Material::DEFAULT_KD), Vec3::ZERO));

    for ((group, material), give) in &checked.faces {
        if give.normals.0 > 0 && give.normals.1 > 0 {
            warnings.push(format!(
                "{}: group '{group}', material '{material}': some faces have normals ('vn') and some do not; shading \
                 them flat",
                path.display()
            ));
        }
    }

    let mut groups = Vec::with_capacity(models.len());
    for model in models {
        let m = &model.mesh;
        // What this model's faces gave, as the checking pass counted them (tobj makes a model per group and
        // material; a material it cannot find is a model without one, `usemtl` still naming it).
        let used = m.material_id.map_or_else(
            || checked.faces.keys().find(|(g, mtl)| *g == model.name && !defined.contains(mtl)),
            |i| checked.faces.keys().find(|(g, mtl)| *g == model.name && *mtl == tobj_materials[i].name),
        );
        let give = used.and_then(|key| checked.faces.get(key)).copied().unwrap_or_default();
        let at = |values: &[f32], i: u32| {
            let i = 3 * i as usize;
            Vec3::new(values[i], values[i + 1], values[i + 2])
        };
        let corners = |values: &[f32], t: &[u32]| [at(values, t[0]), at(values, t[1]), at(values, t[2])];
        let triangles = m.indices.chunks_exact(3).map(|t| corners(&m.positions, t)).collect();
        // Where a face names no normal, tobj makes one up from the previous corner's: such a group is
        // shaded flat (the checking pass found it).
        let smooth = m.normal_indices.len() == m.indices.len() && !m.normal_indices.is_empty() && give.normals.1 == 0;
        let normals = match smooth {
            true => m.normal_indices.chunks_exact(3).map(|t| corners(&m.normals, t)).collect(),
            false => Vec::new(),
        };
        // The same for texture coordinates; the image's rows run down, OBJ's v up.
        let uv = |i: u32| Vec2::new(m.texcoords[2 * i as usize], 1.0 - m.texcoords[2 * i as usize + 1]);
        let textured = m.texcoord_indices.len() == m.indices.len() && !m.texcoord_indices.is_empty() && give.uvs.1 == 0;
        let uvs = match textured {
            true => m.texcoord_indices.chunks_exact(3).map(|t| [uv(t[0]), uv(t[1]), uv(t[2])]).collect(),
            false => Vec::new(),
        };
        let mut material = m.material_id.unwrap_or(default_material);
        if uvs.is_empty() && materials[material].is_textured() {
            let (with, without) = give.uvs;
            let at = give.first_without_uvs.map_or(String::new(), |line| format!(":{line}"));
            warnings.push(format!(
                "{}{at}: group '{}': material '{}' has a texture, but {} of its {} faces here give no texture \
                 coordinates ('vt'); using its Kd and Ke alone there, not cut out",
                path.display(),
                model.name,
                materials[material].name,
                if with == 0 { "all".to_owned() } else { without.to_string() },
                with + without
            ));
            // The material's copy without its texture, for this group alone.
            materials.push(materials[material].untextured());
            material = materials.len() - 1;
        }
        groups.push(Group { name: model.name, material, triangles, normals, uvs, lightmap_uvs: Vec::new() });
    }
    let mut files = files.into_inner();
    let mut images: Vec<PathBuf> =
        textures.by_path.into_iter().filter(|(_, t)| t.is_some()).map(|((path, _), _)| path).collect();
    images.sort();
    images.dedup();
    files.extend(images);
    Ok(Imported { groups, materials, textures: textures.loaded, warnings, files })
}

/// The textures of a material library, each file read once for each use.
#[derive(Default)]
struct TextureFiles {
    loaded: Vec<Texture>,
    /// Index in `loaded` of each file read, `None` where it could not be.
    by_path: std::collections::HashMap<(PathBuf, TextureUse), Option<usize>>,
}

impl TextureFiles {
    /// The index of material `material`'s texture `file`, looked for beside each of `dirs` (the material
    /// libraries), as written then by file name. A missing or unreadable file is a warning, and the material
    /// keeps its `Kd` alone; a file that is no image it can decode is an error.
    fn find(
        &mut self,
        material: &str,
        file: &str,
        usage: TextureUse,
        dirs: &[PathBuf],
        warnings: &mut Vec<String>,
    ) -> Result<Option<usize>, LoadError> {
        let statement = match usage {
            TextureUse::Colour => "map_Kd",
            TextureUse::Emission => "map_Ke",
            TextureUse::Mask => "map_d",
        };
        // `map_Kd -o 1 1 1 wood.png`: options before the name; only the name is used.
        let name = Path::new(file.split_whitespace().last().unwrap_or(file));
        if file.trim_start().starts_with('-') {
            warnings.push(format!("material '{material}': {statement} options ignored in '{file}'"));
        }
        let candidates = dirs.iter().flat_map(|d| [Some(d.join(name)), name.file_name().map(|f| d.join(f))]);
        let Some(path) = candidates.flatten().find(|p| p.is_file()) else {
            let looked = dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ");
            // An absolute path is looked at as written, then by file name beside the libraries.
            let looked = match name.is_absolute() {
                true => format!("looked at it, then for its file name in {looked}"),
                false => format!("looked in {looked}"),
            };
            warnings.push(format!(
                "material '{material}': {statement} texture '{}' not found ({looked}); {}",
                name.display(),
                usage.fallback()
            ));
            return Ok(None);
        };
        // A colour and an emission texture decode alike: one file, one texture.
        let key = (path, usage.decoding());
        if let Some(&index) = self.by_path.get(&key) {
            return Ok(index);
        }
        let path = &key.0;
        let index = match std::fs::read(path) {
            Ok(bytes) => {
                // Its name alone: the error names the path already.
                let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.display().to_string());
                let decoded = match usage {
                    TextureUse::Colour | TextureUse::Emission => Texture::decode(&bytes, &name),
                    TextureUse::Mask => Texture::decode_mask(&bytes, &name),
                };
                let texture = decoded.map_err(|e| error(path, None, format!("material '{material}': {e:#}")))?;
                self.loaded.push(texture);
                Some(self.loaded.len() - 1)
            }
            Err(e) => {
                warnings.push(format!(
                    "material '{material}': cannot read {statement} texture {}: {e}; {}",
                    path.display(),
                    usage.fallback()
                ));
                None
            }
        };
        self.by_path.insert(key, index);
        Ok(index)
    }
}

/// What a material library's texture is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum TextureUse {
    /// `map_Kd`: colour, multiplied by `Kd`.
    Colour,
    /// `map_Ke`: emitted radiance, multiplied by `Ke`; decoded as a colour (sRGB).
    Emission,
    /// `map_d`: a cut-out mask (its alpha, or its red where it has none).
    Mask,
}

impl TextureUse {
    /// What the material does without it.
    fn fallback(self) -> &'static str {
        match self {
            Self::Colour => "using its Kd alone",
            Self::Emission => "using its Ke alone",
            Self::Mask => "not cut out",
        }
    }

    /// How its file is decoded: the same for a colour and an emission texture.
    fn decoding(self) -> Self {
        match self {
            Self::Emission => Self::Colour,
            other => other,
        }
    }
}

/// A text file without its UTF-8 byte order mark. Only a regular file is read: a FIFO or a device named as a
/// mesh (`/dev/zero`) would never end.
fn read_text(path: &Path) -> std::io::Result<String> {
    let kind = std::fs::metadata(path)?.file_type();
    if !kind.is_file() {
        let what = if kind.is_dir() { "it is a directory" } else { "it is not a regular file" };
        return Err(std::io::Error::other(what));
    }
    let text = std::fs::read_to_string(path)?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_owned(),
        None => text,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use check::STRAY_DOTS_SHOWN;

    /// A fresh directory holding `files` (name, content).
    fn files(name: &str, files: &[(&str, &str)]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("sensorlight-obj-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for (file, text) in files {
            std::fs::write(dir.join(file), text).unwrap();
        }
        dir
    }

    /// McGuire's `CornellBox-Sphere.obj`, line 5753: `v  0.2300 1.9900 -0.2200.`.
    #[test]
    fn a_stray_dot_after_a_number_is_read_without_it_and_said() {
        let obj = "v 0 0 0\nv 1 0 0\nv  0.2300 1.9900 -0.2200.\nvn 0 0 1.\nvt 0.5. 1\nf 1 2 3\n";
        let dir = files("stray-dot", &[("mesh.obj", obj)]);
        let data = load(&dir.join("mesh.obj")).unwrap();
        let triangle = data.groups[0].triangles[0];
        assert_eq!(triangle[2], Vec3::new(0.23, 1.99, -0.22));
        let said: Vec<&String> = data.warnings.iter().filter(|w| w.contains("read as")).collect();
        assert_eq!(said.len(), 2, "{:?}", data.warnings); // `1.` is a number as it is
        assert!(said[0].ends_with("mesh.obj:3: '-0.2200.' read as -0.2200"), "{}", said[0]);
        assert!(said[1].ends_with("mesh.obj:5: '0.5.' read as 0.5"), "{}", said[1]);
        // Many are counted, not each said.
        let many: String = (0..9).map(|i| format!("v {i}. 0 0.5.\n")).collect();
        let dir = files("stray-dots", &[("mesh.obj", &(many + "f 1 2 3\n"))]);
        let warnings = load(&dir.join("mesh.obj")).unwrap().warnings;
        assert_eq!(warnings.iter().filter(|w| w.contains("read as")).count(), STRAY_DOTS_SHOWN, "{warnings:?}");
        assert!(
            warnings.iter().any(|w| w.ends_with("mesh.obj: 4 more numbers followed by a stray '.' read without it"))
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Each corner takes the normal its `f` token names; a group where some faces give none is flat, and
    /// said so.
    #[test]
    fn shading_normals_follow_the_faces_normal_indices() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 0.6 0 0.8\n\
                   g smooth\nf 1//1 2//2 3//1\ng mixed\nf 1//1 2//1 3//1\nf 2 4 3\ng flat\nf 1 2 3\n";
        let dir = files("shading-normals", &[("mesh.obj", obj)]);
        let data = load(&dir.join("mesh.obj")).unwrap();
        let group = |name: &str| data.groups.iter().find(|g| g.name == name).unwrap();
        assert_eq!(group("smooth").normals, [[Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::Z]]);
        assert!(group("mixed").normals.is_empty(), "flat: one of its two faces gives no normals");
        assert!(group("flat").normals.is_empty());
        let said: Vec<&String> = data.warnings.iter().filter(|w| w.contains("shading them flat")).collect();
        assert!(said.len() == 1 && said[0].contains("'mixed'"), "{:?}", data.warnings);
    }

    #[test]
    fn garbage_is_still_refused_with_its_line() {
        for bad in ["1.2.3", "abc", "1e", "1e.", ".", "-.", "1..", "1.2.3."] {
            let dir = files("garbage", &[("mesh.obj", &format!("v 0 0 0\nv 1 {bad} 0\n"))]);
            let e = load(&dir.join("mesh.obj")).err().unwrap_or_else(|| panic!("{bad} accepted"));
            assert_eq!(e.line, Some(2), "{bad}");
            assert!(e.to_string().contains(&format!("not a number: '{bad}'")), "{bad}: {e}");
        }
    }
}
