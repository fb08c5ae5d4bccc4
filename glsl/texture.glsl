// Colour textures as the G-buffer samples them: the GPU twin of src/scene/texture.rs (`Texture::sample`),
// from the same packed sRGB texels (that file draws their layout). The includer binds the table and the
// texels at TEXTURE_BINDING and TEXTURE_BINDING + 1 of set 0.
#ifndef TEXTURE_GLSL
#define TEXTURE_GLSL
#include "types.glsl"

layout(std430, set = 0, binding = TEXTURE_BINDING) readonly buffer TextureTable { GpuTexture texture_table[]; };
layout(std430, set = 0, binding = TEXTURE_BINDING + 1) readonly buffer Texels { uint texels[]; };

float srgb_to_linear(float c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

vec4 decode_texel(uint t) {
    vec4 c = unpackUnorm4x8(t);
    return vec4(srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b), c.a);
}

// Level `level` of `t`: its first texel and size.
uint level_offset(GpuTexture t, uint level, out ivec2 size) {
    uint offset = t.offset;
    uvec2 s = uvec2(t.width, t.height);
    for (uint l = 0u; l < level; l++) {
        offset += s.x * s.y;
        s = max(s / 2u, uvec2(1u));
    }
    size = ivec2(s);
    return offset;
}

// Bilinear at `uv` (repeating) within the level at `offset` of `size`; texel centres at half-integers.
vec4 bilinear(uint offset, ivec2 size, vec2 uv) {
    vec2 xy = (uv - floor(uv)) * vec2(size) - 0.5;
    vec2 base = floor(xy);
    vec2 f = xy - base;
    ivec2 i = ivec2(base);
    vec4 c[4];
    for (int k = 0; k < 4; k++) {
        ivec2 at = i + ivec2(k & 1, k >> 1);
        at = ((at % size) + size) % size;
        c[k] = decode_texel(texels[offset + uint(at.y * size.x + at.x)]);
    }
    return mix(mix(c[0], c[1], f.x), mix(c[2], c[3], f.x), f.y);
}

// Linear colour and alpha of texture `index` at `uv`, on level of detail `lod` (blending the two levels
// around it), as `Texture::sample`.
//
// The next level's offset is one step on from the first's, not a second walk from level 0: in the reduction
// lavapipe returned wrong texels from two such walks whose lengths differed between neighbouring invocations
// (glsl/sky.glsl, which reads its levels alike). The textured room renders the same either way here.
vec4 sample_texture(uint index, vec2 uv, float lod) {
    GpuTexture t = texture_table[index];
    lod = clamp(lod, 0.0, float(t.levels - 1u));
    float lower = floor(lod);
    ivec2 size;
    uint offset = level_offset(t, uint(lower), size);
    vec4 a = bilinear(offset, size, uv);
    if (lod == lower) {
        return a;
    }
    offset += uint(size.x * size.y);
    size = max(size / 2, ivec2(1));
    return mix(a, bilinear(offset, size, uv), lod - lower);
}

// The level of detail on which a step of `dx` or `dy` in uv spans one texel (Vulkan's scale factor ρ, the
// larger axis, in texels of level 0): 0 where the texture is magnified.
float texture_lod(uint index, vec2 dx, vec2 dy) {
    GpuTexture t = texture_table[index];
    vec2 size = vec2(t.width, t.height);
    float rho = max(length(dx * size), length(dy * size));
    return rho > 0.0 ? log2(rho) : 0.0;
}

// Whether surface `s` is cut out at `uv` (obj::Cutout; the CPU's twin is the BVH's `Cutouts::opaque`):
// its cut-out texture's alpha, bilinear on level 0, under its threshold.
bool cut_out(GpuSurface s, vec2 uv) {
    return s.alpha_map != 0u && sample_texture(s.alpha_map - 1u, uv, 0.0).a < s.alpha_threshold;
}

// Sub-samples per side of a pixel's footprint.
const uint FOOTPRINT_SIDE = 4u;

// The mean of texture `index` over the fragment's pixel: FOOTPRINT_SIDE² samples at the centres of a grid
// over the pixel's square, carried to texture space by uv's screen derivatives, each on the level where its
// share of the footprint is one texel (Vulkan's scale factor ρ, the larger axis), level 0 where the texture
// is magnified. A pixel's colour is the mean over its square (what the oracle integrates); one bilinear
// sample at its centre would be a point, up to twice off on a checker seen about one texel a pixel.
// `dx`, `dy`: dFdx(uv), dFdy(uv), taken by the caller in uniform control flow.
vec4 sample_footprint(uint index, vec2 uv, vec2 dx, vec2 dy) {
    float lod = texture_lod(index, dx / float(FOOTPRINT_SIDE), dy / float(FOOTPRINT_SIDE));
    vec4 sum = vec4(0.0);
    for (uint j = 0u; j < FOOTPRINT_SIDE; j++) {
        for (uint i = 0u; i < FOOTPRINT_SIDE; i++) {
            vec2 o = (vec2(i, j) + 0.5) / float(FOOTPRINT_SIDE) - 0.5;
            sum += sample_texture(index, uv + o.x * dx + o.y * dy, lod);
        }
    }
    return sum / float(FOOTPRINT_SIDE * FOOTPRINT_SIDE);
}
#endif
