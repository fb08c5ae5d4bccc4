//! What a file holds, by its first bytes and then its extension: so that an image or a mesh given where a
//! scene file is expected is named as such, not reported as a TOML syntax error on some line.

use std::io::Read as _;
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A scene file (TOML): anything not recognised as another kind.
    Scene,
    ObjMesh,
    /// glTF 2.0: `.gltf` (JSON) or `.glb` (binary).
    GltfMesh,
    MtlLibrary,
    Exr,
    Png,
    /// Bytes that are not text and no image known here.
    Binary,
}

impl FileKind {
    /// The kind of the file at `path`. An unreadable file counts as a scene file, so that reading it reports
    /// why it cannot be read.
    pub fn of(path: &Path) -> Self {
        let mut head = Vec::new();
        let read = std::fs::File::open(path).and_then(|f| f.take(4096).read_to_end(&mut head));
        if read.is_err() {
            return Self::Scene;
        }
        match Self::sniff(&head) {
            // A `.glb` whose magic is wrong: its loader says what is wrong with it.
            Some(Self::Binary) if Self::by_extension(path) == Self::GltfMesh => Self::GltfMesh,
            sniffed => sniffed.unwrap_or_else(|| Self::by_extension(path)),
        }
    }

    /// The kind the content shows, if it shows one.
    fn sniff(head: &[u8]) -> Option<Self> {
        if head.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            return Some(Self::Exr);
        }
        if head.starts_with(b"\x89PNG\r\n\x1a\n") {
            return Some(Self::Png);
        }
        if head.starts_with(b"glTF") {
            return Some(Self::GltfMesh);
        }
        // The head may end inside a UTF-8 sequence: judge the valid prefix.
        let text = match std::str::from_utf8(head) {
            Ok(text) => text,
            Err(e) if e.error_len().is_none() => std::str::from_utf8(&head[..e.valid_up_to()]).ok()?,
            Err(_) => return Some(Self::Binary),
        };
        if text.contains('\0') {
            return Some(Self::Binary);
        }
        // The first statement: OBJ and MTL open with keywords no scene file starts a line with.
        let first = text.lines().map(str::trim).find(|l| !l.is_empty() && !l.starts_with('#'))?;
        let keyword = first.split_whitespace().next()?;
        match keyword {
            "v" | "vn" | "vt" | "f" | "o" | "g" | "s" | "mtllib" | "usemtl" => Some(Self::ObjMesh),
            "newmtl" => Some(Self::MtlLibrary),
            _ => None,
        }
    }

    fn by_extension(path: &Path) -> Self {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("obj") => Self::ObjMesh,
            Some("gltf" | "glb") => Self::GltfMesh,
            Some("mtl") => Self::MtlLibrary,
            Some("exr") => Self::Exr,
            Some("png") => Self::Png,
            _ => Self::Scene,
        }
    }

    /// Whether it is a mesh `render` takes alone (the camera then frames it).
    pub fn is_mesh(self) -> bool {
        matches!(self, Self::ObjMesh | Self::GltfMesh)
    }

    /// What it is, for messages: "an OBJ mesh".
    pub fn describe(self) -> &'static str {
        match self {
            Self::Scene => "a scene file (TOML)",
            Self::ObjMesh => "an OBJ mesh",
            Self::GltfMesh => "a glTF mesh",
            Self::MtlLibrary => "an MTL material library",
            Self::Exr => "an OpenEXR image",
            Self::Png => "a PNG image",
            Self::Binary => "a binary file",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn content_decides_then_the_extension() {
        assert_eq!(FileKind::sniff(b"\x89PNG\r\n\x1a\n...."), Some(FileKind::Png));
        assert_eq!(FileKind::sniff(&[0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0]), Some(FileKind::Exr));
        assert_eq!(FileKind::sniff(b"# a mesh\n\nmtllib a.mtl\nv 0 0 0\n"), Some(FileKind::ObjMesh));
        assert_eq!(FileKind::sniff(b"v 0 0 0\nv 1 0 0\n"), Some(FileKind::ObjMesh));
        assert_eq!(FileKind::sniff(b"newmtl red\nKd 1 0 0\n"), Some(FileKind::MtlLibrary));
        assert_eq!(FileKind::sniff(b"mesh = \"a.obj\"\n[camera]\n"), None);
        assert_eq!(FileKind::sniff(b"\xff\xfe\x00binary"), Some(FileKind::Binary));
        assert_eq!(FileKind::by_extension(Path::new("a/b.OBJ")), FileKind::ObjMesh);
        assert_eq!(FileKind::by_extension(Path::new("a/b.gltf")), FileKind::GltfMesh);
        assert_eq!(FileKind::sniff(b"glTF\x02\x00\x00\x00"), Some(FileKind::GltfMesh));
        assert_eq!(FileKind::by_extension(Path::new("scene.toml")), FileKind::Scene);
    }
}
