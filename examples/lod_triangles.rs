//! Triangles a sensor's views would draw with cluster culling and LOD (the CPU twin of the culling pass)
//! against the full mesh every view draws today: `cargo run --release --example lod_triangles --
//! scene.toml [sensors] [rd]`. Sensors (hemicube, a zoom pair per light group) sit on the centroids of
//! triangles picked evenly through the mesh.
use sensorlight::clusters::cache;
use sensorlight::gpu_types::GpuCluster;
use sensorlight::light::groups::Lights;
use sensorlight::passes::cull::{gpu_clusters, keeps};
use sensorlight::passes::cull_triangles::may_cover;
use sensorlight::sensors::SensorKind;
use sensorlight::sensors::frame::{self, SensorFrame};
use sensorlight::sensors::layout::SensorLayout;
use sensorlight::sensors::views::BatchViews;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or_else(|| anyhow::anyhow!("usage: lod_triangles SCENE.toml [sensors] [rd]"))?;
    let sensors: usize = args.get(2).map_or(Ok(200), |s| s.parse())?;
    let rd: u32 = args.get(3).map_or(Ok(64), |s| s.parse())?;
    let scene = sensorlight::scene::Scene::load(std::path::Path::new(path))?;
    let mesh = &scene.mesh;
    let (hierarchy, _) = cache::load_or_build(mesh, cache::default_dir().as_deref());
    let gpu: Vec<GpuCluster> = gpu_clusters(&hierarchy, |s| mesh.material_of(s).is_emitter());
    let lights = Lights::new(mesh);
    let bounds: Vec<_> = lights.groups.iter().map(|g| g.bounds).collect();
    let layout = SensorLayout { kind: SensorKind::Hemicube, groups: bounds.len() as u32 };
    let scale = mesh.scale();
    let frames: Vec<SensorFrame> = (0..sensors)
        .map(|i| {
            let t = &mesh.triangles[(i * 7919 + 13) % mesh.triangles.len()];
            SensorFrame::new((t.v[0] + t.v[1] + t.v[2]) / 3.0, t.normal, frame::BIAS * scale)
        })
        .collect();
    let near = frame::NEAR * scale;
    let batch = BatchViews::new(&frames, &layout, near, &bounds, rd);
    let start = std::time::Instant::now();
    let (mut drawn, mut commands, mut covering) = (0u64, 0u64, 0u64);
    let corner = |i: u32| glam::Vec3::from(hierarchy.positions[hierarchy.indices[i as usize] as usize]);
    for (v, view) in batch.views.iter().enumerate() {
        let sensor = &batch.sensors[v / batch.per_sensor];
        for k in gpu.iter().filter(|k| keeps(k, view, sensor, rd, near)) {
            drawn += (k.index_count / 3) as u64;
            commands += 1;
            let first = k.first_index;
            covering += (first..first + k.index_count)
                .step_by(3)
                .filter(|&i| may_cover(view, rd, [corner(i), corner(i + 1), corner(i + 2)]))
                .count() as u64;
        }
    }
    let full = mesh.triangles.len() as u64 * batch.views.len() as u64;
    println!(
        "{} triangles, {} clusters; {sensors} sensors × {} views at rd {rd}: full detail {:.0} triangles/sensor, \
         culled+LOD {:.0} triangles/sensor in {:.1} draws/sensor ({:.2} %), of which {:.0} may cover a texel; \
         twin {:.2} s",
        mesh.triangles.len(),
        gpu.len(),
        batch.per_sensor,
        full as f64 / sensors as f64,
        drawn as f64 / sensors as f64,
        commands as f64 / sensors as f64,
        100.0 * drawn as f64 / full as f64,
        covering as f64 / sensors as f64,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
