//! A camera for a bare mesh, so that `render mesh.obj` shows it lit without a scene file. Outside
//! ([`frame`]): it frames the mesh's bounding box. Inside ([`inside`]): a closed room with its light inside
//! (Bitterli's *veach ajar*) seen from outside is its roof, black; when the mesh encloses its own centre
//! (rays from the box's centre hit it in at least [`ENCLOSED`] of [`PROBE_RAYS`] directions) and light
//! reaches it, the camera stands at the centre and looks along the longest horizontal axis, with a
//! [`INSIDE_VFOV_DEG`] field of view. Light reaches the centre where an emitter faces it (the camera then
//! looks towards the side whose emitters send it more light; on a tie, the side with the farther wall), or
//! where what the probes meet is lit, by an emitter's front it sees or through one bounce
//! ([`BOUNCE_RAYS`] more rays from each): a lamp in the next room, behind the door ajar, facing away (the
//! camera then looks towards the side that shows more lit surface). A closed mesh whose emitters all face
//! out (a lit object, not a room) keeps the outside view: from inside it nothing lit would be seen.

use anyhow::Result;
use glam::Vec3;

use super::bvh::Bvh;
use super::{Aabb, Camera, ImageSize, Mesh, Ray, triangle_area};

/// Full vertical field of view of the automatic camera, degrees: a normal lens, little distortion.
pub const VFOV_DEG: f32 = 40.0;
/// Image size for a bare mesh, as the shipped scenes'.
pub const DEFAULT_IMAGE: ImageSize = ImageSize { width: 256, height: 256 };
/// An axis counts as thin (the mesh is a floor plan, a wall) below this fraction of the largest extent.
const THIN: f32 = 0.25;
/// Room around the box's projection, as a factor of the distance that just fits it.
const MARGIN: f32 = 1.05;
/// How far a camera that sees the mesh from the side looks down on it, degrees: a floor is not seen
/// edge-on, and a model shows its top. Not where the mesh is open towards the camera (a box seen through
/// its opening, whose ceiling and lamp a view from above would hide behind its front edge).
pub const ELEVATION_DEG: f32 = 15.0;
/// The camera turns round to the other side of its axis when that side shows this much more front-facing
/// area: a box open on one side (the Cornell box, a room without its fourth wall) is seen through the
/// opening, and a closed mesh, about as much front on either side, keeps the usual side.
const TURN: f32 = 1.2;

/// Directions probed from the box's centre to decide whether the mesh encloses it (a Fibonacci sphere:
/// deterministic, even).
pub const PROBE_RAYS: usize = 256;
/// The share of [`PROBE_RAYS`] that must hit the mesh for it to enclose its centre: a box open on one side
/// (the Cornell box) lets about a sixth of them out; a room with a door ajar or a window a few per cent.
pub const ENCLOSED: f32 = 0.95;
/// Full vertical field of view of a camera inside: wide enough to show a room's walls, floor and ceiling.
pub const INSIDE_VFOV_DEG: f32 = 65.0;
/// Rays from each probe's hit (a Fibonacci hemisphere about its normal) looking for lit surfaces beyond it:
/// the light's one bounce into a room no emitter faces.
pub const BOUNCE_RAYS: usize = 64;
/// Points on the emitters that the probes' shadow rays look for, at most (spread over the emitters by
/// triangle, each its centroid).
const EMITTER_POINTS: usize = 256;

/// The automatic camera of `mesh` (see the module documentation): inside when the mesh encloses its lit
/// centre, else [`frame`]d from outside. The flag says which.
pub fn for_mesh(mesh: &Mesh, size: ImageSize) -> Result<(Camera, Placement)> {
    if let Some(camera) = inside(mesh)? {
        return Ok((camera, Placement::Inside));
    }
    let front_area = |forward: Vec3| -> f32 {
        mesh.triangles.iter().map(|t| triangle_area(&t.v) * (-t.normal.dot(forward)).max(0.0)).sum()
    };
    Ok((frame(&framed_bounds(mesh), size, front_area)?, Placement::Outside))
}

/// What the outside camera frames: the mesh without its emitters, where it has anything else. A panel that
/// only lights the scene (a sky above a gazebo, a large area light) would otherwise set the frame, and
/// the model would be a few pixels in its middle; an emitter within the model is inside its box anyway.
fn framed_bounds(mesh: &Mesh) -> Aabb {
    let mut bounds = Aabb::EMPTY;
    for t in mesh.triangles.iter().filter(|t| !mesh.material_of(t.surface).is_emitter()) {
        t.v.iter().for_each(|&p| bounds.grow(p));
    }
    if bounds.min.cmple(bounds.max).all() { bounds } else { mesh.bounds }
}

/// Where [`for_mesh`] put the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// Outside the mesh, framing its bounding box.
    Outside,
    /// At the centre of a mesh that encloses it (a closed room).
    Inside,
}

/// The camera inside `mesh`, if the mesh encloses its bounding box's centre and light reaches that centre
/// (see the module documentation); `None` otherwise.
pub fn inside(mesh: &Mesh) -> Result<Option<Camera>> {
    let centre = mesh.bounds.center();
    let emitters: Vec<&super::Triangle> =
        mesh.triangles.iter().filter(|t| mesh.material_of(t.surface).ke.max_element() > 0.0).collect();
    if emitters.is_empty() {
        return Ok(None); // nothing lit to see from inside: the cheap answer first, before any ray
    }
    let bvh = Bvh::of_mesh(mesh);
    let eps = 1e-5 * mesh.scale();
    let hit = |from: Vec3, dir: Vec3| bvh.intersect(&Ray::new(from, dir), eps, f32::INFINITY);
    let probes: Vec<(Vec3, Option<super::bvh::Hit>)> =
        (0..PROBE_RAYS).map(|k| fibonacci_direction(k, PROBE_RAYS)).map(|d| (d, hit(centre, d))).collect();
    if (probes.iter().filter(|(_, h)| h.is_some()).count() as f32) < ENCLOSED * PROBE_RAYS as f32 {
        return Ok(None);
    }
    // Light each emitter sends towards the centre (area × luminance × cosine at the emitter), and where from.
    let lights: Vec<(Vec3, f32)> = (emitters.iter())
        .filter_map(|t| {
            let ke = mesh.material_of(t.surface).ke;
            let at = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
            let cosine = t.normal.dot((centre - at).normalize_or_zero());
            let power = triangle_area(&t.v) * ke.dot(Vec3::new(0.2126, 0.7152, 0.0722)) * cosine;
            (power > 0.0).then_some((at, power))
        })
        .collect();
    // Else, how lit what each probe meets is: 1 where it sees an emitter's front, else the share of its
    // bounce rays that meet a surface that does.
    let lit_along: Vec<(Vec3, f32)> = if lights.is_empty() {
        let step = emitters.len().div_ceil(EMITTER_POINTS);
        let points: Vec<(Vec3, Vec3)> =
            emitters.iter().step_by(step).map(|t| ((t.v[0] + t.v[1] + t.v[2]) / 3.0, t.normal)).collect();
        let surface = |from: Vec3, dir: Vec3, h: &super::bvh::Hit| {
            let n = mesh.triangles[h.triangle as usize].normal;
            (from + dir * h.t, if n.dot(dir) > 0.0 { -n } else { n })
        };
        let sees_light = |(p, n): (Vec3, Vec3)| {
            points.iter().any(|&(q, m)| {
                let d = q - p;
                d.dot(n) > 0.0 && m.dot(d) < 0.0 && !bvh.occluded(&Ray::new(p + n * eps, d), 0.0, 1.0 - 1e-4)
            })
        };
        let lit = |(d, h): &(Vec3, Option<super::bvh::Hit>)| -> f32 {
            let Some(h) = h else { return 0.0 };
            let (p, n) = surface(centre, *d, h);
            if sees_light((p, n)) {
                return 1.0;
            }
            let (t, b) = n.any_orthonormal_pair();
            let beyond = (0..BOUNCE_RAYS).filter(|&k| {
                let l = fibonacci_direction(k, 2 * BOUNCE_RAYS); // the upper half of the sphere: z > 0
                let dir = t * l.x + b * l.y + n * l.z;
                hit(p + n * eps, dir).is_some_and(|h2| sees_light(surface(p + n * eps, dir, &h2)))
            });
            beyond.count() as f32 / BOUNCE_RAYS as f32
        };
        probes.iter().map(|probe| (probe.0, lit(probe))).collect()
    } else {
        Vec::new()
    };
    if lights.is_empty() && lit_along.iter().all(|&(_, w)| w == 0.0) {
        return Ok(None); // enclosed, but no light reaches what the centre sees
    }
    let extent = mesh.bounds.max - mesh.bounds.min;
    let axis = if extent.x > extent.z { Vec3::X } else { Vec3::Z };
    let light_towards = |d: Vec3| -> f32 {
        match lights.is_empty() {
            false => lights.iter().map(|&(at, power)| power * (at - centre).normalize_or_zero().dot(d).max(0.0)).sum(),
            true => lit_along.iter().map(|&(along, w)| w * along.dot(d).max(0.0)).sum(),
        }
    };
    let (ahead, behind) = (light_towards(-axis), light_towards(axis));
    let open = |d: Vec3| hit(centre, d).map_or(f32::INFINITY, |h| h.t);
    // Within 1 % the lights are a tie (a lamp overhead): then the wider view; −axis where that ties too.
    let forward = if (ahead - behind).abs() > 0.01 * ahead.max(behind) {
        if ahead >= behind { -axis } else { axis }
    } else if open(axis) > open(-axis) {
        axis
    } else {
        -axis
    };
    Camera::look_at(centre, centre + forward, Vec3::Y, INSIDE_VFOV_DEG).map(Some)
}

/// Direction `k` of `n` on a Fibonacci sphere (golden-angle spiral, even in area).
fn fibonacci_direction(k: usize, n: usize) -> Vec3 {
    let z = 1.0 - (2.0 * k as f32 + 1.0) / n as f32;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = k as f32 * std::f32::consts::PI * (3.0 - 5f32.sqrt());
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A camera that sees all of `bounds` in an image of `size`: it looks along −z (y up), or, when the box is
/// thin along x or y, across that thinnest extent. Along that axis it looks from the side whose faces turn
/// their fronts to it (`front_area(forward)` is the mesh's area facing a camera that looks along
/// `forward`); from the side, it looks down by [`ELEVATION_DEG`] unless the mesh is open towards it. It
/// stands where the box's eight corners just fit the image ([`MARGIN`]), so that the mesh fills the frame.
pub fn frame(bounds: &Aabb, size: ImageSize, front_area: impl Fn(Vec3) -> f32) -> Result<Camera> {
    let extent = bounds.max - bounds.min;
    let largest = extent.max_element();
    let (mut forward, mut up) = if extent.y < THIN * largest && extent.y <= extent.x.min(extent.z) {
        (Vec3::NEG_Y, Vec3::NEG_Z) // seen from above, −z at the top
    } else if extent.x < THIN * largest && extent.x <= extent.z {
        (Vec3::NEG_X, Vec3::Y)
    } else {
        (Vec3::NEG_Z, Vec3::Y)
    };
    if front_area(-forward) > TURN * front_area(forward) {
        forward = -forward;
        if forward == Vec3::Y {
            up = Vec3::Z; // seen from below, +z at the top
        }
    }
    let open_towards_camera = front_area(forward) > TURN * front_area(-forward);
    if forward.y == 0.0 && !open_towards_camera {
        let elevation = ELEVATION_DEG.to_radians();
        forward = forward * elevation.cos() - Vec3::Y * elevation.sin();
    }
    // The distance at which every corner projects within the image: a corner at `x` across and `z` beyond
    // the target needs `|x| / (d + z) ≤ tan(half field of view) / MARGIN`. Perspective draws the far
    // corners smaller, so the target then moves to the middle of the corners' projection and the distance
    // is fitted again (a few times: each fit moves the middle a little).
    let right = forward.cross(up).normalize();
    let true_up = right.cross(forward);
    let (tan_v, aspect) = ((0.5 * VFOV_DEG.to_radians()).tan(), size.width as f32 / size.height as f32);
    let radius = (0.5 * extent.length()).max(f32::MIN_POSITIVE);
    let corners = bounds.corners();
    // Each corner seen from a target: across, up and beyond it.
    let seen = |target: Vec3| {
        corners
            .iter()
            .map(move |&c| (c - target).dot(right))
            .zip(corners.iter().map(move |&c| ((c - target).dot(true_up), (c - target).dot(forward))))
    };
    let fit = |target: Vec3| {
        seen(target)
            .map(|(x, (y, z))| (MARGIN * (x.abs() / (tan_v * aspect)).max(y.abs() / tan_v) - z).max(1e-3 * radius - z))
            .fold(f32::MIN_POSITIVE, f32::max)
    };
    let (mut center, mut distance) = (bounds.center(), fit(bounds.center()));
    for _ in 0..4 {
        let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
        for (x, (y, z)) in seen(center) {
            let at = glam::Vec2::new(x, y) / (distance + z);
            (lo, hi) = (lo.min(at), hi.max(at));
        }
        let middle = 0.5 * (lo + hi) * distance;
        center += right * middle.x + true_up * middle.y;
        distance = fit(center);
    }
    Camera::look_at(center - forward * distance, center, up, VFOV_DEG)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every corner of `bounds` projects inside the image, in front of the camera.
    fn assert_framed(bounds: Aabb, size: ImageSize) {
        assert_framed_camera(&bounds, size, &frame(&bounds, size, |_| 0.0).unwrap());
    }

    fn assert_framed_camera(bounds: &Aabb, size: ImageSize, camera: &Camera) {
        let bounds = *bounds;
        let near = 1e-4 * bounds.diagonal();
        let view_proj = camera.view_proj(size.width, size.height, near);
        for corner in bounds.corners() {
            let clip = view_proj * corner.extend(1.0);
            assert!(clip.w > near, "corner {corner} behind the camera ({bounds:?}, {size:?})");
            let ndc = clip.truncate().truncate() / clip.w;
            assert!(ndc.abs().max_element() <= 1.0, "corner {corner} at {ndc} is outside ({bounds:?}, {size:?})");
        }
    }

    #[test]
    fn the_whole_box_is_in_view() {
        let boxes = [
            Aabb { min: Vec3::new(-1.0, 0.0, -1.0), max: Vec3::new(1.0, 2.0, 1.0) },
            Aabb { min: Vec3::new(0.0, 0.0, 0.0), max: Vec3::new(555.0, 548.8, 559.2) },
            Aabb { min: Vec3::new(-5.0, -0.01, -3.0), max: Vec3::new(5.0, 0.01, 3.0) }, // a floor: from above
            Aabb { min: Vec3::new(10.0, 0.0, 0.0), max: Vec3::new(10.1, 3.0, 4.0) },    // a wall across x
            Aabb { min: Vec3::new(-1e-3, 2e-3, 5.0), max: Vec3::new(1e-3, 3e-3, 5.002) },
        ];
        let sizes = [(256, 256), (640, 120), (90, 400), (1, 1)];
        for bounds in boxes {
            for (width, height) in sizes {
                assert_framed(bounds, ImageSize { width, height });
            }
        }
    }

    #[test]
    fn a_flat_mesh_is_seen_across_its_thin_side() {
        let floor = Aabb { min: Vec3::new(-5.0, 0.0, -3.0), max: Vec3::new(5.0, 0.1, 3.0) };
        assert_eq!(frame(&floor, DEFAULT_IMAGE, |_| 0.0).unwrap().forward, Vec3::NEG_Y);
        let cube = Aabb { min: Vec3::ZERO, max: Vec3::ONE };
        assert!(frame(&cube, DEFAULT_IMAGE, |_| 0.0).unwrap().forward.dot(Vec3::NEG_Z) > 0.96);
    }

    /// Seen from the side, a mesh is looked down on by [`ELEVATION_DEG`] (a floor is not edge-on), and
    /// its box fills the image's narrower side but for the margin (issue 42, item 7: a bare mesh filled
    /// half the frame); a box open towards the camera is seen straight through its opening.
    #[test]
    fn a_mesh_seen_from_the_side_is_looked_down_on_and_fills_the_frame() {
        let cube = Aabb { min: Vec3::ZERO, max: Vec3::splat(2.0) };
        for (width, height) in [(256, 256), (640, 240), (200, 400)] {
            let size = ImageSize { width, height };
            let camera = frame(&cube, size, |_| 0.0).unwrap();
            let down = (-camera.forward.y).asin().to_degrees();
            assert!((down - ELEVATION_DEG).abs() < 1e-3, "looks down {down}°");
            assert_framed_camera(&cube, size, &camera);
            // The corners' extent across the narrower side of the image, in normalised device coordinates.
            let view_proj = camera.view_proj(width, height, 1e-3);
            let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
            for corner in cube.corners() {
                let clip = view_proj * corner.extend(1.0);
                let ndc = clip.truncate().truncate() / clip.w;
                (lo, hi) = (lo.min(ndc), hi.max(ndc));
            }
            let filled = if width <= height { hi.x - lo.x } else { hi.y - lo.y };
            assert!(filled > 2.0 / MARGIN - 0.05, "{width}×{height}: the box spans {filled} of 2");
        }
        let open = |forward: Vec3| if forward == Vec3::NEG_Z { 5.0 } else { 1.0 };
        assert_eq!(frame(&cube, DEFAULT_IMAGE, open).unwrap().forward, Vec3::NEG_Z);
    }

    /// A box open towards −z shows its inside's fronts to a camera looking along +z: it turns round. About
    /// as much front either way (a closed mesh) keeps −z.
    #[test]
    fn an_open_box_is_seen_through_its_opening() {
        let cube = Aabb { min: Vec3::ZERO, max: Vec3::ONE };
        let open_towards_neg_z = |forward: Vec3| if forward == Vec3::Z { 5.0 } else { 1.0 };
        assert_eq!(frame(&cube, DEFAULT_IMAGE, open_towards_neg_z).unwrap().forward, Vec3::Z);
        let closed = |forward: Vec3| if forward == Vec3::Z { 1.1 } else { 1.0 };
        assert!(frame(&cube, DEFAULT_IMAGE, closed).unwrap().forward.dot(Vec3::NEG_Z) > 0.96);
        let floor = Aabb { min: Vec3::new(-5.0, 0.0, -3.0), max: Vec3::new(5.0, 0.1, 3.0) };
        let ceiling = |forward: Vec3| if forward == Vec3::Y { 5.0 } else { 0.0 };
        let below = frame(&floor, DEFAULT_IMAGE, ceiling).unwrap();
        assert_eq!(below.forward, Vec3::Y);
        assert_framed_camera(&floor, DEFAULT_IMAGE, &below);
    }
}

#[cfg(test)]
mod inside_tests {
    use super::*;
    use crate::scene::builtin::{from_groups, rect};
    use crate::scene::material::Material;

    /// A closed box 4 × 2.5 × 6 (longest along z) with a light panel on the wall at z = `light_z` facing
    /// `facing`; `open` leaves out the +z wall.
    fn room(light_z: f32, facing: Vec3, open: bool) -> Mesh {
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        let c = Vec3::new(0.0, 1.25, 0.0);
        let mut groups = vec![
            ("floor", 0, rect(Vec3::ZERO, 2.0 * x, 3.0 * z, y)),
            ("ceiling", 0, rect(2.5 * y, 2.0 * x, 3.0 * z, -y)),
            ("left", 0, rect(c - 2.0 * x, 3.0 * z, 1.25 * y, x)),
            ("right", 0, rect(c + 2.0 * x, 3.0 * z, 1.25 * y, -x)),
            ("back", 0, rect(c - 3.0 * z, 2.0 * x, 1.25 * y, z)),
            ("light", 1, rect(Vec3::new(0.0, 1.25, light_z), 0.3 * x, 0.3 * y, facing)),
        ];
        if !open {
            groups.push(("front", 0, rect(c + 3.0 * z, 2.0 * x, 1.25 * y, -z)));
        }
        let m = |name: &str, kd: f32, ke: f32| Material::new(name, Vec3::splat(kd), Vec3::splat(ke));
        let camera = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        from_groups(groups, vec![m("white", 0.7, 0.0), m("light", 0.0, 5.0)], camera, DEFAULT_IMAGE).mesh
    }

    #[test]
    fn a_closed_room_gets_a_camera_inside_looking_towards_its_light() {
        for (light_z, facing, forward) in [(-2.9, Vec3::Z, Vec3::NEG_Z), (2.9, Vec3::NEG_Z, Vec3::Z)] {
            let (camera, placement) = for_mesh(&room(light_z, facing, false), DEFAULT_IMAGE).unwrap();
            assert_eq!(placement, Placement::Inside);
            assert_eq!(camera.eye, Vec3::new(0.0, 1.25, 0.0));
            assert!(camera.forward.abs_diff_eq(forward, 1e-6), "{} towards the light at z {light_z}", camera.forward);
            assert!((camera.vfov.to_degrees() - INSIDE_VFOV_DEG).abs() < 1e-3);
        }
    }

    /// A lamp that faces the back wall, away from the centre (as Bitterli's *veach ajar* lamp, in the next
    /// room): what the probes meet is lit, so the camera stands inside, looking towards the lit wall.
    #[test]
    fn a_room_lit_by_a_lamp_facing_away_gets_a_camera_inside() {
        let (camera, placement) = for_mesh(&room(-2.9, Vec3::NEG_Z, false), DEFAULT_IMAGE).unwrap();
        assert_eq!(placement, Placement::Inside);
        assert!(camera.forward.abs_diff_eq(Vec3::NEG_Z, 1e-6), "{} towards the lit back wall", camera.forward);
    }

    #[test]
    fn an_open_box_or_a_light_facing_out_keeps_the_outside_camera() {
        assert_eq!(for_mesh(&room(-2.9, Vec3::Z, true), DEFAULT_IMAGE).unwrap().1, Placement::Outside);
        // A lit object, not a room: its only light faces away from the centre.
        assert_eq!(for_mesh(&room(-3.01, Vec3::NEG_Z, false), DEFAULT_IMAGE).unwrap().1, Placement::Outside);
    }

    /// A model under a panel that only lights it (the gazebo's sky, 40 × 40 m, 20 m up) is framed without
    /// the panel: the model is not a few pixels in the middle of the panel's frame.
    #[test]
    fn a_panel_that_only_lights_is_left_out_of_the_frame() {
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        let groups = vec![
            ("floor", 0, rect(Vec3::ZERO, 2.0 * x, 2.0 * z, y)),
            ("post", 0, rect(Vec3::new(0.0, 1.0, 0.0), 0.2 * x, 1.0 * y, z)),
            ("sky", 1, rect(20.0 * y, 20.0 * x, 20.0 * z, -y)),
        ];
        let m = |name: &str, kd: f32, ke: f32| Material::new(name, Vec3::splat(kd), Vec3::splat(ke));
        let camera = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        let mesh = from_groups(groups, vec![m("white", 0.7, 0.0), m("sky", 0.0, 1.0)], camera, DEFAULT_IMAGE).mesh;
        let framed = framed_bounds(&mesh);
        assert_eq!((framed.min, framed.max), (Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 2.0, 2.0)));
        let (camera, placement) = for_mesh(&mesh, DEFAULT_IMAGE).unwrap();
        assert_eq!(placement, Placement::Outside);
        assert!(camera.eye.length() < 20.0, "the camera frames the model, not the sky: {}", camera.eye);
    }

    #[test]
    fn probe_directions_are_unit_and_cover_the_sphere() {
        let dirs: Vec<Vec3> = (0..PROBE_RAYS).map(|k| fibonacci_direction(k, PROBE_RAYS)).collect();
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-5));
        let mean = dirs.iter().sum::<Vec3>() / PROBE_RAYS as f32;
        assert!(mean.length() < 0.02, "even: mean {mean}");
    }
}
