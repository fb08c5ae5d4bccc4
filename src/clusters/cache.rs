//! Built hierarchies kept on disk, one file per mesh, keyed by a hash of the mesh (positions, surface ids,
//! which surfaces emit) and [`BUILD_VERSION`]: a second render of a large mesh starts without rebuilding.
//! The cache is advisory: a missing, unreadable, foreign or damaged file is rebuilt, never an error.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use bytemuck::Pod;

use super::{BUILD_VERSION, Cluster, ClusterMesh, MAX_TRIANGLES, build};
use crate::scene::Mesh;

const MAGIC: &[u8; 8] = b"SLCLUST\0";

/// `$SENSORLIGHT_CACHE_DIR`, else `$XDG_CACHE_HOME/sensorlight`, else `~/.cache/sensorlight` (as the
/// strategy cache), or none.
pub fn default_dir() -> Option<PathBuf> {
    std::env::var_os("SENSORLIGHT_CACHE_DIR").map(PathBuf::from).or_else(|| {
        std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .map(|d| d.join("sensorlight"))
    })
}

/// A 64-bit hash of what the hierarchy depends on: the build, every triangle's corners and surface, and
/// which surfaces emit.
pub fn mesh_key(mesh: &Mesh) -> u64 {
    let mut h = Mix(0x5e45_0c1a_u64 ^ ((BUILD_VERSION as u64) << 32) ^ MAX_TRIANGLES as u64);
    for t in &mesh.triangles {
        for p in t.v {
            h.word((p.x.to_bits() as u64) << 32 | p.y.to_bits() as u64);
            h.word(p.z.to_bits() as u64);
        }
        h.word(t.surface as u64);
    }
    for id in 1..=mesh.surfaces.len() as u32 {
        h.word(mesh.material_of(id).is_emitter() as u64);
    }
    h.0
}

/// SplitMix64's finaliser over a running state: cheap, and every input bit reaches every output bit.
struct Mix(u64);

impl Mix {
    fn word(&mut self, x: u64) {
        let mut z = (self.0 ^ x).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        self.0 = z ^ (z >> 31);
    }
}

/// Where [`load_or_build`] keeps `mesh`'s hierarchy in `dir`.
pub fn path(dir: &Path, mesh: &Mesh) -> PathBuf {
    dir.join(format!("clusters-{:016x}.bin", mesh_key(mesh)))
}

/// The hierarchy of `mesh`: read from `dir` if it holds this mesh's, else built and written there (a write
/// that fails is reported in the second value, not an error). With no `dir`, built.
pub fn load_or_build(mesh: &Mesh, dir: Option<&Path>) -> (ClusterMesh, Option<String>) {
    let Some(dir) = dir else { return (build(mesh), None) };
    let key = mesh_key(mesh);
    let file = dir.join(format!("clusters-{key:016x}.bin"));
    if let Some(clusters) = std::fs::read(&file).ok().and_then(|bytes| decode(&bytes, key)) {
        return (clusters, None);
    }
    let clusters = build(mesh);
    let note = store(&file, &encode(&clusters, key))
        .err()
        .map(|e| format!("cannot cache the cluster hierarchy in {}: {e}", file.display()));
    (clusters, note)
}

/// Written to a temporary file and renamed, so that a reader never sees half a file.
fn store(file: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = file.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let tmp =
        dir.join(format!(".{}.{}.tmp", file.file_name().unwrap_or_default().to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, file)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Magic, version, key, the four array lengths, then the arrays (little-endian, as bytemuck lays them).
pub fn encode(c: &ClusterMesh, key: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + c.bytes());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&BUILD_VERSION.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&key.to_le_bytes());
    for n in [c.positions.len(), c.vertex_surface.len(), c.indices.len(), c.clusters.len()] {
        out.extend_from_slice(&(n as u64).to_le_bytes());
    }
    out.extend_from_slice(bytemuck::cast_slice(&c.positions));
    out.extend_from_slice(bytemuck::cast_slice(&c.vertex_surface));
    out.extend_from_slice(bytemuck::cast_slice(&c.indices));
    out.extend_from_slice(bytemuck::cast_slice(&c.clusters));
    out
}

/// The hierarchy in `bytes` if they hold one of this build for `key`, complete and consistent.
pub fn decode(bytes: &[u8], key: u64) -> Option<ClusterMesh> {
    let mut r = Reader(bytes);
    if r.take(8)? != MAGIC || r.u32()? != BUILD_VERSION || r.u32()? != 0 || r.u64()? != key {
        return None;
    }
    let lens: Vec<usize> = (0..4).map(|_| r.u64().and_then(|n| usize::try_from(n).ok())).collect::<Option<_>>()?;
    let c = ClusterMesh {
        positions: r.array(lens[0])?,
        vertex_surface: r.array(lens[1])?,
        indices: r.array(lens[2])?,
        clusters: r.array::<Cluster>(lens[3])?,
    };
    let vertices = c.positions.len();
    let consistent = r.0.is_empty()
        && c.vertex_surface.len() == vertices
        && c.indices.iter().all(|&v| (v as usize) < vertices)
        && c.clusters
            .iter()
            .all(|k| (k.first_index as u64 + k.index_count as u64) <= c.indices.len() as u64 && k.index_count % 3 == 0);
    consistent.then_some(c)
}

struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        if self.0.len() < n {
            return None;
        }
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        Some(head)
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    /// `n` values, copied (the file's bytes need not be aligned for `T`).
    fn array<T: Pod>(&mut self, n: usize) -> Option<Vec<T>> {
        let bytes = self.take(n.checked_mul(size_of::<T>())?)?;
        Some(bytemuck::pod_collect_to_vec(bytes))
    }
}
