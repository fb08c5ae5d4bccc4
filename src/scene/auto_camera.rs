//! A camera for a bare mesh: it frames the mesh's bounding box, so that `render mesh.obj` shows the whole
//! mesh without a scene file.

use anyhow::Result;
use glam::Vec3;

use super::{Aabb, Camera, ImageSize};

/// Full vertical field of view of the automatic camera, degrees: a normal lens, little distortion.
pub const VFOV_DEG: f32 = 40.0;
/// Image size for a bare mesh, as the shipped scenes'.
pub const DEFAULT_IMAGE: ImageSize = ImageSize { width: 256, height: 256 };
/// An axis counts as thin (the mesh is a floor plan, a wall) below this fraction of the largest extent.
const THIN: f32 = 0.25;
/// Room around the bounding sphere, as a factor of the distance that just fits it.
const MARGIN: f32 = 1.05;
/// The camera turns round to the other side of its axis when that side shows this much more front-facing
/// area: a box open on one side (the Cornell box, a room without its fourth wall) is seen through the
/// opening, and a closed mesh, about as much front on either side, keeps the usual side.
const TURN: f32 = 1.2;

/// A camera that sees all of `bounds` in an image of `size`: it looks along −z (y up), or, when the box is
/// thin along x or y, across that thinnest extent, from a distance at which the box's bounding sphere fits
/// the narrower of the two fields of view. Along that axis it looks from the side whose faces turn their
/// fronts to it: `front_area(forward)` is the mesh's area facing a camera that looks along `forward`.
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
    let radius = (0.5 * extent.length()).max(f32::MIN_POSITIVE);
    let half_v = 0.5 * VFOV_DEG.to_radians();
    let half_h = (half_v.tan() * size.width as f32 / size.height as f32).atan();
    let distance = MARGIN * radius / half_v.min(half_h).sin();
    let center = bounds.center();
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
        for i in 0..8 {
            let pick = |bit: usize, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            let corner = Vec3::new(
                pick(1, bounds.min.x, bounds.max.x),
                pick(2, bounds.min.y, bounds.max.y),
                pick(4, bounds.min.z, bounds.max.z),
            );
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
        assert_eq!(frame(&cube, DEFAULT_IMAGE, |_| 0.0).unwrap().forward, Vec3::NEG_Z);
    }

    /// A box open towards −z shows its inside's fronts to a camera looking along +z: it turns round. About
    /// as much front either way (a closed mesh) keeps −z.
    #[test]
    fn an_open_box_is_seen_through_its_opening() {
        let cube = Aabb { min: Vec3::ZERO, max: Vec3::ONE };
        let open_towards_neg_z = |forward: Vec3| if forward == Vec3::Z { 5.0 } else { 1.0 };
        assert_eq!(frame(&cube, DEFAULT_IMAGE, open_towards_neg_z).unwrap().forward, Vec3::Z);
        let closed = |forward: Vec3| if forward == Vec3::Z { 1.1 } else { 1.0 };
        assert_eq!(frame(&cube, DEFAULT_IMAGE, closed).unwrap().forward, Vec3::NEG_Z);
        let floor = Aabb { min: Vec3::new(-5.0, 0.0, -3.0), max: Vec3::new(5.0, 0.1, 3.0) };
        let ceiling = |forward: Vec3| if forward == Vec3::Y { 5.0 } else { 0.0 };
        let below = frame(&floor, DEFAULT_IMAGE, ceiling).unwrap();
        assert_eq!(below.forward, Vec3::Y);
        assert_framed_camera(&floor, DEFAULT_IMAGE, &below);
    }
}
