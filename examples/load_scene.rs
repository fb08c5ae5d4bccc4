//! Loads a scene and reports its size and the time taken: `cargo run --release --example load_scene -- scene.toml`.
//! Measure peak memory with `/usr/bin/time -v`.
fn main() -> anyhow::Result<()> {
    let path = std::env::args().nth(1).ok_or_else(|| anyhow::anyhow!("usage: load_scene SCENE.toml"))?;
    let start = std::time::Instant::now();
    let scene = sensorlight::scene::Scene::load(std::path::Path::new(&path))?;
    println!(
        "{} triangles, {} surfaces in {:.2} s",
        scene.mesh.triangles.len(),
        scene.mesh.surfaces.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
