//! Loads a scene and reports its size and the time taken; with `--clusters`, also its cluster hierarchy
//! (from the cache, else built and cached): `cargo run --release --example load_scene -- scene.toml
//! [--clusters]`. Measure peak memory with `/usr/bin/time -v`.
fn main() -> anyhow::Result<()> {
    let path = std::env::args().nth(1).ok_or_else(|| anyhow::anyhow!("usage: load_scene SCENE.toml [--clusters]"))?;
    let start = std::time::Instant::now();
    let scene = sensorlight::scene::Scene::load(std::path::Path::new(&path))?;
    println!(
        "{} triangles, {} surfaces in {:.2} s",
        scene.mesh.triangles.len(),
        scene.mesh.surfaces.len(),
        start.elapsed().as_secs_f64()
    );
    if std::env::args().any(|a| a == "--clusters") {
        let start = std::time::Instant::now();
        let dir = sensorlight::clusters::cache::default_dir();
        let (c, note) = sensorlight::clusters::cache::load_or_build(&scene.mesh, dir.as_deref());
        let levels = c.clusters.iter().map(|k| k.depth).max().unwrap_or(0) + 1;
        println!(
            "{} clusters over {levels} levels, {} triangles in all, {:.0} MB, in {:.2} s{}",
            c.clusters.len(),
            c.indices.len() / 3,
            c.bytes() as f64 / 1e6,
            start.elapsed().as_secs_f64(),
            note.map(|n| format!(" ({n})")).unwrap_or_default()
        );
    }
    Ok(())
}
