//! Rust ↔ GLSL struct layouts: member offsets and array strides read out of the compiled SPIR-V of
//! `glsl/layout_probe.comp` (binding k holds an array of the k-th shared struct) against `src/gpu_types.rs`.

use std::collections::HashMap;
use std::mem::offset_of;

use sensorlight::gpu_types::{
    ComposePush, CullPush, EmitterPush, ExactInterpolatePush, GBufferPush, GpuCacheGrid, GpuCacheSlot, GpuCacheSplit,
    GpuCluster, GpuCullNode, GpuDrawCommand, GpuEmitter, GpuEmitterChunk, GpuLightGroup, GpuQuad, GpuSensor,
    GpuSensorResult, GpuSensorView, GpuSky, GpuSubSample, GpuSupersampledPixel, GpuSurface, GpuTexture, GpuZoom,
    ImagePush, ReducePush, ResolvePush, SensorComputePush, SensorPush, TransportPush,
};
use sensorlight::shaders;

const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_ARRAY_STRIDE: u32 = 6;
const DECORATION_BINDING: u32 = 33;
const DECORATION_OFFSET: u32 = 35;

/// For each descriptor binding: the element struct's member offsets and the array stride.
fn layouts(spirv: &[u8]) -> HashMap<u32, (Vec<u32>, u32)> {
    let words: Vec<u32> = spirv.chunks_exact(4).map(|b| u32::from_le_bytes(b.try_into().unwrap())).collect();
    assert_eq!(words[0], 0x0723_0203, "not SPIR-V");
    let (mut binding, mut stride) = (HashMap::new(), HashMap::new());
    let mut offsets: HashMap<u32, Vec<(u32, u32)>> = HashMap::new();
    let (mut pointee, mut variable_type) = (HashMap::new(), HashMap::new());
    let (mut struct_members, mut array_element) = (HashMap::new(), HashMap::new());
    let mut i = 5;
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let w = &words[i..i + count];
        match op {
            OP_DECORATE if w[2] == DECORATION_BINDING => {
                binding.insert(w[1], w[3]);
            }
            OP_DECORATE if w[2] == DECORATION_ARRAY_STRIDE => {
                stride.insert(w[1], w[3]);
            }
            OP_MEMBER_DECORATE if w[3] == DECORATION_OFFSET => offsets.entry(w[1]).or_default().push((w[2], w[4])),
            OP_TYPE_POINTER => {
                pointee.insert(w[1], w[3]);
            }
            OP_VARIABLE => {
                variable_type.insert(w[2], w[1]);
            }
            OP_TYPE_STRUCT => {
                struct_members.insert(w[1], w[2..].to_vec());
            }
            OP_TYPE_RUNTIME_ARRAY => {
                array_element.insert(w[1], w[2]);
            }
            _ => {}
        }
        i += count;
    }
    let mut out = HashMap::new();
    for (variable, b) in binding {
        // variable → pointer → block struct → member 0 (runtime array) → element struct
        let block = pointee[&variable_type[&variable]];
        let array = struct_members[&block][0];
        let element = array_element[&array];
        let mut members = offsets.remove(&element).unwrap_or_default();
        members.sort();
        assert_eq!(members.len(), struct_members[&element].len(), "every member has an offset");
        out.insert(b, (members.into_iter().map(|(_, offset)| offset).collect(), stride[&array]));
    }
    out
}

macro_rules! rust_layout {
    ($t:ty: $($field:ident),+) => {
        (vec![$(offset_of!($t, $field) as u32),+], size_of::<$t>() as u32)
    };
}

#[test]
fn shared_structs_match_glsl() {
    let glsl = layouts(shaders::LAYOUT_PROBE_COMP);
    let rust = [
        (0, "GpuSurface", rust_layout!(GpuSurface: kd, ke, kd_factor, kd_map, ke_map, alpha_map, alpha_threshold)),
        (1, "GBufferPush", rust_layout!(GBufferPush: view_proj)),
        (2, "GpuSensorView", rust_layout!(GpuSensorView: view_proj, clip, eye, layer, flags, _pad)),
        (3, "SensorPush", rust_layout!(SensorPush: epsilon, first_view, layer_base, exact, emission_scale, cache)),
        (
            4,
            "ReducePush",
            rust_layout!(
                ReducePush: rd,
                layers,
                main_layers,
                atlas_columns,
                groups,
                chunks,
                emission_scale,
                main_entries
            ),
        ),
        (5, "GpuQuad", rust_layout!(GpuQuad: x0, y0, x1, y1, own_x1, own_y1, _pad)),
        (6, "ImagePush", rust_layout!(ImagePush: width, height, radius, count)),
        (7, "GpuSensor", rust_layout!(GpuSensor: origin, t, b, n)),
        (8, "GpuZoom", rust_layout!(GpuZoom: right, up, forward)),
        (9, "GpuEmitter", rust_layout!(GpuEmitter: v0, v1, v2, ke)),
        (10, "GpuLightGroup", rust_layout!(GpuLightGroup: first_chunk, chunks, _pad)),
        (11, "GpuSensorResult", rust_layout!(GpuSensorResult: r, visibility, rest)),
        (12, "GpuEmitterChunk", rust_layout!(GpuEmitterChunk: first, count, group, _pad)),
        (13, "EmitterPush", rust_layout!(EmitterPush: sensors, chunks, groups, _pad)),
        (
            14,
            "GpuCluster",
            rust_layout!(
                GpuCluster: sphere,
                slab,
                box_min,
                box_max,
                own_min,
                own_max,
                parent_min,
                parent_max,
                first_index,
                index_count,
                flags,
                _pad,
                part_min,
                part_max
            ),
        ),
        (
            15,
            "GpuDrawCommand",
            rust_layout!(GpuDrawCommand: index_count, instance_count, first_index, vertex_offset, first_instance),
        ),
        (
            16,
            "CullPush",
            rust_layout!(
                CullPush: views,
                per_sensor,
                max_per_view,
                rd,
                near,
                root,
                step,
                in_base,
                out_base,
                out_capacity,
                in_capacity,
                region,
                _pad
            ),
        ),
        (
            17,
            "GpuCullNode",
            rust_layout!(
                GpuCullNode: sphere,
                own_min,
                own_max,
                parent_min,
                parent_max,
                first,
                count,
                flags,
                _pad
            ),
        ),
        (18, "GpuCacheGrid", rust_layout!(GpuCacheGrid: origin, dims, entries, _pad)),
        (19, "GpuCacheSlot", rust_layout!(GpuCacheSlot: key, entry, _pad)),
        (20, "GpuCacheSplit", rust_layout!(GpuCacheSplit: plane, children, _pad)),
        (21, "ComposePush", rust_layout!(ComposePush: background, width, height, apart, sky)),
        (22, "ExactInterpolatePush", rust_layout!(ExactInterpolatePush: width, count, groups, bias)),
        (
            23,
            "GpuSubSample",
            rust_layout!(
                GpuSubSample: position,
                normal,
                albedo,
                own,
                donor,
                weight,
                _pad,
                visibility,
                donor_visibility
            ),
        ),
        (25, "GpuSupersampledPixel", rust_layout!(GpuSupersampledPixel: emission, pixel, _pad)),
        (24, "ResolvePush", rust_layout!(ResolvePush: width, count, samples, groups, bias, exact, _pad)),
        (26, "GpuTexture", rust_layout!(GpuTexture: offset, width, height, levels)),
        (27, "GpuSky", rust_layout!(GpuSky: width, height, levels, _pad, rotation)),
        (
            28,
            "SensorComputePush",
            rust_layout!(
                SensorComputePush: clear,
                sensor,
                rd,
                layers,
                per_sensor,
                layer_count,
                triangles,
                max_per_view,
                culled,
                count_buffer,
                _pad
            ),
        ),
        (29, "TransportPush", rust_layout!(TransportPush: rd, layers, main_layers, atlas_columns)),
    ];
    assert_eq!(glsl.len(), rust.len(), "layout_probe.comp and this test list different structs");
    for (binding, name, expected) in rust {
        assert_eq!(glsl[&binding], expected, "{name}: (member offsets, size) in GLSL vs Rust");
    }
}

/// The integer constants `glsl/types.glsl` declares (`const uint NAME = VALUE;`), by name.
fn glsl_constants() -> HashMap<String, u64> {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/glsl/types.glsl")).unwrap();
    (text.lines())
        .filter_map(|line| line.trim().strip_prefix("const uint "))
        .map(|rest| {
            let (name, value) = rest.split_once('=').unwrap();
            let value = value.split(';').next().unwrap().trim().trim_end_matches('u');
            let value = match value.strip_prefix("0x") {
                Some(hex) => u64::from_str_radix(hex, 16).unwrap(),
                None => value.parse().unwrap(),
            };
            (name.trim().to_owned(), value)
        })
        .collect()
}

/// Constants the shaders and the host both hold have one value: a bound the host relies on (the deepest
/// split tree a lookup walks, the entry bits of a transport map) cannot drift apart unseen.
#[test]
fn shared_constants_match_glsl() {
    use sensorlight::gpu_types as g;
    let glsl = glsl_constants();
    let rust: [(&str, u64); 12] = [
        ("VIEW_EMITTERS_ONLY", g::VIEW_EMITTERS_ONLY as u64),
        ("VIEW_ZOOM", g::VIEW_ZOOM as u64),
        ("MAX_GROUPS", g::MAX_GROUPS as u64),
        ("CACHE_ENTRY_BITS", g::CACHE_ENTRY_BITS as u64),
        ("CACHE_SPLIT", sensorlight::gi::SPLIT as u64),
        ("CACHE_SPLIT_DEPTH", g::CACHE_SPLIT_DEPTH as u64),
        ("TRANSPORT_NONE", g::TRANSPORT_NONE as u64),
        ("NO_SURFACE", sensorlight::scene::NO_SURFACE as u64),
        ("CLUSTER_EMITTER", g::CLUSTER_EMITTER as u64),
        ("NODE_LEAF", g::NODE_LEAF as u64),
        ("CLUSTER_CLOSED", g::CLUSTER_CLOSED as u64),
        ("KEPT_BACK_HIDDEN", g::KEPT_BACK_HIDDEN as u64),
    ];
    for (name, value) in rust {
        assert_eq!(glsl.get(name), Some(&value), "{name}: glsl/types.glsl against Rust");
    }
}
