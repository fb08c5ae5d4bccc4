// The projected solid angle of an emitter triangle seen from a sensor, clipped to the sensor's domain:
// the GPU twin of src/light/polygon.rs (Lambert's formula, Arvo 1995 eq. 7), step for step.
//
//   Omega_perp = 1/2 * sum_i Theta_i * n . (r_{i+1} x r_i) / |r_{i+1} x r_i|,   Theta_i = angle(r_i, r_{i+1})
//
// with r_i the clipped polygon's vertices relative to the sensor's origin. The triangle emits from its front
// only (counter-clockwise seen from the front), so one whose front does not face the origin gives 0.
#ifndef POLYGON_GLSL
#define POLYGON_GLSL

// A triangle clipped by up to 4 planes through the origin keeps at most 7 vertices.
const int MAX_POLYGON = 7;

// atan(t) for t in [0, 1], to about an ulp (Cephes' atanf). Vulkan allows a driver's atan to be 4096 ulp
// off (2.4e-4 relative), which would be the largest error of the exact term.
float atan_unit(float t) {
    float base = 0.0;
    float x = t;
    if (t > 0.41421356237) {  // tan(pi / 8): reduce by pi / 4
        base = 0.78539816340;
        x = (t - 1.0) / (t + 1.0);
    }
    float z = x * x;
    return base + ((((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1) * z * x + x);
}

// The angle between two vectors whose cross product has length y >= 0 and dot product x: atan2(y, x) in
// [0, pi], with an argument kept in [0, 1] so that nearly parallel and nearly opposite vectors stay exact.
float angle_between(float y, float x) {
    float ax = abs(x);
    float a = atan_unit(min(y, ax) / max(y, ax));
    if (y > ax) {
        a = 1.57079632679 - a;
    }
    return x < 0.0 ? 3.14159265359 - a : a;
}

// Keeps the part of `poly` (count vertices, relative to the origin) with dot(m, r) >= 0.
void clip_half_space(inout vec3 poly[MAX_POLYGON], inout int count, vec3 m) {
    vec3 out_poly[MAX_POLYGON];
    int n = 0;
    for (int i = 0; i < count; i++) {
        vec3 a = poly[i];
        vec3 b = poly[(i + 1) % count];
        float da = dot(m, a);
        float db = dot(m, b);
        if (da >= 0.0 && n < MAX_POLYGON) {
            out_poly[n++] = a;
        }
        if ((da >= 0.0) != (db >= 0.0) && n < MAX_POLYGON) {
            out_poly[n++] = a + (b - a) * (da / (da - db));
        }
    }
    for (int i = 0; i < n; i++) {
        poly[i] = out_poly[i];
    }
    count = n;
}

// One edge's term of Lambert's sum: Theta * n . (b x a) / |b x a|.
float lambert_edge(vec3 a, vec3 b, vec3 n) {
    vec3 c = cross(b, a);
    float len = length(c);
    // An atan keeps Theta accurate for nearly parallel vertices, where acos does not.
    return len > 0.0 ? angle_between(len, dot(a, b)) * dot(n, c) / len : 0.0;
}

// Lambert's sum over a polygon relative to the receiving point, wound counter-clockwise seen from its front,
// which faces the point.
float lambert(vec3 poly[MAX_POLYGON], int count, vec3 n) {
    float sum = 0.0;
    for (int i = 0; i < count; i++) {
        sum += lambert_edge(poly[i], poly[(i + 1) % count], n);
    }
    return 0.5 * sum;
}

// Omega_perp of triangle (v0, v1, v2) seen from sensor `s`, clipped to its domain (the hemisphere above
// its tangent plane, or its square frustum of half-width s.origin.w).
float projected_solid_angle(GpuSensor s, vec3 v0, vec3 v1, vec3 v2) {
    vec3 o = s.origin.xyz;
    vec3 r0 = v0 - o;
    vec3 r1 = v1 - o;
    vec3 r2 = v2 - o;
    if (dot(cross(r1 - r0, r2 - r0), -r0) <= 0.0) {
        return 0.0;  // seen from behind or edge-on
    }
    vec3 n = s.n.xyz;
    float half_width = s.origin.w;
    // Wholly inside the domain, as most emitters are: the same sum without the clipping's arrays, which a
    // CPU driver keeps in memory (the emitter pass 1.6x faster on lavapipe with 10 000 emitters).
    bool inside = dot(n, r0) >= 0.0 && dot(n, r1) >= 0.0 && dot(n, r2) >= 0.0;
    if (half_width != 0.0) {
        vec3 t = s.t.xyz;
        vec3 b = s.b.xyz;
        for (int k = 0; k < 4 && inside; k++) {
            vec3 m = n * half_width + (k == 0 ? -t : k == 1 ? t : k == 2 ? -b : b);
            inside = dot(m, r0) >= 0.0 && dot(m, r1) >= 0.0 && dot(m, r2) >= 0.0;
        }
    }
    if (inside) {
        return 0.5 * (lambert_edge(r0, r1, n) + lambert_edge(r1, r2, n) + lambert_edge(r2, r0, n));
    }
    vec3 poly[MAX_POLYGON];
    poly[0] = r0;
    poly[1] = r1;
    poly[2] = r2;
    int count = 3;
    if (half_width == 0.0) {
        clip_half_space(poly, count, n);
    } else {
        vec3 t = s.t.xyz;
        vec3 b = s.b.xyz;
        clip_half_space(poly, count, n * half_width - t);
        if (count >= 3) clip_half_space(poly, count, n * half_width + t);
        if (count >= 3) clip_half_space(poly, count, n * half_width - b);
        if (count >= 3) clip_half_space(poly, count, n * half_width + b);
    }
    return count >= 3 ? lambert(poly, count, n) : 0.0;
}
#endif
