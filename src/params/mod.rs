//! The algorithm's parameters: one place for their defaults, ranges and checks. A value comes from a
//! command-line flag, else the scene file's `[render]` table, else the table's default (`table.rs`); an error names the
//! parameter as the user wrote it there (`--tile` on the command line, `[render] tile` in a scene file).

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;

use crate::sensors::SensorKind;
pub use crate::sensors::SensorShape;
pub use crate::sensors::refine::Region;

#[macro_use]
pub(crate) mod declare;
pub mod flags;
mod kinds;
mod overrides;
mod param;
mod table;

pub use declare::{EstimatorDefault, Fallback};
pub use kinds::{Antialiasing, Bounces, EstimatorKind, Indirect};
pub use param::{Origin, ParamError};
pub use table::{
    DEFAULT_EPSILON, DEFAULT_ESTIMATOR, DEFAULT_FILTER_RADIUS, MAX_CACHE_RESOLUTION, MAX_FILTER_RADIUS, Overrides,
    Param, Values,
};

/// `render`'s and `reference`'s light: global illumination until converged.
pub const DEFAULT_INDIRECT: Indirect = Indirect::Bounces(Bounces::Converged);

/// What a sensor sees (docs/DESIGN.md §1–2); shared by the GPU renderer and the CPU reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorParams {
    /// `hemicube` (default; the whole hemisphere) or `frustum` (the paper's single view of `fov`).
    pub sensor: SensorKind,
    /// What a sensor sees on a non-emitting surface: the paper's `Kd·ε`, or the light it reflects.
    pub indirect: Indirect,
    /// Radiance of rays that leave the scene (linear RGB, ≥ 0). Default black.
    pub background: Vec3,
}

/// What one render does with its sensors, beyond what they are (the renderer's construction settings):
/// refinement, filter and the estimator's constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameParams {
    /// The model of indirect light and the background (see [`EstimatorParams`]).
    pub indirect: Indirect,
    pub background: Vec3,
    /// dt: initial grid step of the adaptive refinement (paper §III-G), a power of two ≥ 1; 16 typical.
    pub tile: u32,
    /// Largest relative variation of R, and of each light group's visibility, between a quad's corners that
    /// is still interpolated; ≥ 0. 0 senses every pixel; 0.1–0.4 typical (0.2: every shipped and hard scene
    /// within 1 % of the oracle with the exact estimator; 0.1 halves the error in 1.4× the time); a huge value
    /// senses only the grid (and the light hints' boundaries).
    pub dradiance: f32,
    /// Radius in pixels of the id-constrained Gaussian filter (paper §III-H), σ = radius / 2; 0 = off. It
    /// keeps to the centre pixel's surface and light mask; the exact estimator leaves it little noise to
    /// remove, so it is off by default there.
    pub filter_radius: u32,
    /// With global illumination and the exact estimator: the same filter's radius for R's indirect part
    /// alone (the light the maps see on surfaces), 0 … [`MAX_FILTER_RADIUS`]. The direct light keeps its
    /// sharp shadows; the indirect, smooth but aliased where it comes through a gap a texel wide (a door
    /// ajar), loses its pixel-to-pixel noise. Its own radius where it differs from `filter_radius`.
    pub indirect_filter_radius: u32,
    /// Whether a pixel is its centre or its square.
    pub aa: Antialiasing,
    /// Only these pixels need be right (a tile): the sensors go only where the refinement's quads meet
    /// them grown by the margin the filters and the supersampling read across, but for the first grid,
    /// sensed everywhere (its brightest R sets the refinement's dark floor), so that each pixel of the
    /// region is what the whole image's render gives it. `None`: the whole image.
    pub region: Option<Region>,
}

impl FrameParams {
    /// Every pixel sensed at its centre and nothing filtered: R exactly as the sensors give it (probes,
    /// benchmarks, comparisons with the oracle).
    pub const fn every_pixel(indirect: Indirect, background: Vec3) -> Self {
        Self {
            indirect,
            background,
            tile: 1,
            dradiance: 0.0,
            filter_radius: 0,
            indirect_filter_radius: 0,
            aa: Antialiasing::Off,
            region: None,
        }
    }
}

/// Everything `render` resolves from flags, the scene file and defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderParams {
    /// Each parameter as resolved on its own (see the table, `table.rs`, for ranges and typical values).
    pub values: Values,
    /// What a sensor sees, from the values that decide it together: the sensor's shape and field of view,
    /// the one model of indirect light (ε or bounces), the background. Read this, not those values.
    pub estimator: EstimatorParams,
    /// Where each value that was set came from (absent: the default).
    origins: BTreeMap<Param, Origin>,
}

impl RenderParams {
    /// Resolves flags over the scene file's `[render]` values (`scene`: its path and values) over the
    /// defaults, and checks every value given, each with its origin (a bad value in the scene file is an
    /// error even where a flag overrides it).
    pub fn resolve(scene: Option<(&Path, &Overrides)>, flags: &Overrides) -> Result<Self, ParamError> {
        let empty = Overrides::default();
        let (scene_path, scene) = scene.map_or((None, &empty), |(p, o)| (Some(p), o));
        let scene_origin = scene_path.map_or(Origin::Default, |p| Origin::SceneFile(p.to_owned()));
        scene.check(&scene_origin)?;
        flags.check(&Origin::Flag)?;

        let mut origins = BTreeMap::new();
        let kind = flags.estimator.or(scene.estimator).unwrap_or(DEFAULT_ESTIMATOR);
        let values = Values::resolve(flags, scene, &scene_origin, kind, &mut origins);
        // One model: a flag of either kind overrides the scene file's, whichever kind that set.
        let set_at = |param, level| origins.get(&param) == Some(level);
        let indirect = [Origin::Flag, scene_origin]
            .iter()
            .find_map(|level| {
                let epsilon = set_at(Param::Epsilon, level).then_some(Indirect::Epsilon(values.epsilon));
                epsilon.or(set_at(Param::Bounces, level).then_some(Indirect::Bounces(values.bounces)))
            })
            .unwrap_or(DEFAULT_INDIRECT);
        // The model not chosen was not used: its value is not said to come from anywhere.
        match indirect {
            Indirect::Epsilon(_) => origins.remove(&Param::Bounces),
            Indirect::Bounces(_) => origins.remove(&Param::Epsilon),
        };
        let sensor = SensorKind::new(values.sensor, values.fov_deg);
        let estimator = EstimatorParams { sensor, indirect, background: Vec3::from(values.background) };
        let params = Self { values, estimator, origins };
        if let Some(problem) = sensor.size_problem(params.values.sensor_size, u32::MAX) {
            return Err(params.attribute(ParamError::new(Param::SensorSize, problem)));
        }
        if let Some(problem) = sensor.size_problem(params.values.cache_sensor_size, u32::MAX) {
            return Err(params.attribute(ParamError::new(Param::CacheSensorSize, problem)));
        }
        Ok(params)
    }

    /// The per-render part.
    pub fn frame(&self) -> FrameParams {
        let v = &self.values;
        FrameParams {
            indirect: self.estimator.indirect,
            background: self.estimator.background,
            tile: v.tile,
            dradiance: v.dradiance,
            filter_radius: v.filter_radius,
            indirect_filter_radius: v.indirect_filter_radius,
            aa: v.aa,
            region: None,
        }
    }

    /// Values that are valid but probably not what was meant, each with the reason: a field of view given
    /// to hemicube sensors (which ignore it), and an `ε` brighter than every emitter of the scene (whose
    /// brightest `Ke` component is `brightest_emission`), which then dominates the image.
    pub fn warnings(&self, brightest_emission: f32) -> Vec<String> {
        let mut warnings = Vec::new();
        let fov = self.origin(Param::Fov);
        if matches!(self.estimator.sensor, SensorKind::Hemicube) && fov != Origin::Default {
            warnings.push(format!(
                "{}: ignored by hemicube sensors, which see the whole hemisphere (a field of view is the \
                 frustum sensor's: {} frustum)",
                Param::Fov.as_set(&fov),
                Param::Sensor.as_set(&fov)
            ));
        }
        if let Indirect::Epsilon(epsilon) = self.estimator.indirect
            && brightest_emission > 0.0
            && epsilon > brightest_emission
        {
            warnings.push(format!(
                "{} {epsilon} is brighter than every emitter (the brightest Ke component is {brightest_emission}): \
                 every surface then returns Kd·ε, and the constant term dominates the image",
                Param::Epsilon.as_set(&self.origin(Param::Epsilon))
            ));
        }
        warnings
    }

    /// Where `param`'s value came from.
    pub fn origin(&self, param: Param) -> Origin {
        self.origins.get(&param).cloned().unwrap_or(Origin::Default)
    }

    /// `error` with the origin of its parameter's value, so that it names the flag or the scene file.
    pub fn attribute(&self, mut error: ParamError) -> ParamError {
        if error.origin.is_none() {
            error.origin = Some(self.origin(error.param));
        }
        error
    }
}

impl EstimatorParams {
    /// The estimator part of [`RenderParams::resolve`].
    pub fn resolve(scene: Option<(&Path, &Overrides)>, flags: &Overrides) -> Result<Self, ParamError> {
        Ok(RenderParams::resolve(scene, flags)?.estimator)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precedence_is_flag_then_scene_then_default() {
        let scene = Overrides { epsilon: Some(0.5), tile: Some(8), ..Default::default() };
        let flags = Overrides { epsilon: Some(0.25), ..Default::default() };
        let path = Path::new("room.toml");
        let p = RenderParams::resolve(Some((path, &scene)), &flags).unwrap();
        assert_eq!((p.estimator.indirect, p.values.tile, p.values.sensor_size), (Indirect::Epsilon(0.25), 8, 32));
        let paper =
            RenderParams::resolve(None, &Overrides { estimator: Some(EstimatorKind::Paper), ..Default::default() });
        let paper = paper.unwrap();
        assert_eq!(
            (paper.values.sensor_size, paper.values.filter_radius),
            (256, 2),
            "the paper's estimator keeps its defaults"
        );
        assert_eq!(p.estimator.sensor, SensorKind::Hemicube);
        assert_eq!(p.origin(Param::Epsilon), Origin::Flag);
        assert_eq!(p.origin(Param::Tile), Origin::SceneFile(path.into()));
        assert_eq!(p.origin(Param::SensorSize), Origin::Default);
    }

    /// Global illumination by default; `--epsilon` or `--bounces` choose the model, a flag of either kind
    /// over the scene file's of either kind; both at one level is an error naming them.
    #[test]
    fn one_model_of_indirect_light_is_chosen() {
        let path = Path::new("s.toml");
        let resolve = |scene: Overrides, flags: Overrides| RenderParams::resolve(Some((path, &scene)), &flags);
        let none = Overrides::default;
        assert_eq!(resolve(none(), none()).unwrap().estimator.indirect, DEFAULT_INDIRECT);
        assert_eq!(DEFAULT_INDIRECT, Indirect::Bounces(Bounces::Converged));
        let eps = |e| Overrides { epsilon: Some(e), ..Default::default() };
        let bounces = |b| Overrides { bounces: Some(b), ..Default::default() };
        let p = resolve(eps(0.0), bounces(Bounces::Fixed(2))).unwrap();
        assert_eq!(
            (p.estimator.indirect, p.origin(Param::Bounces)),
            (Indirect::Bounces(Bounces::Fixed(2)), Origin::Flag)
        );
        let p = resolve(bounces(Bounces::Converged), eps(0.3)).unwrap();
        assert_eq!((p.estimator.indirect, p.origin(Param::Epsilon)), (Indirect::Epsilon(0.3), Origin::Flag));
        let p = resolve(eps(0.0), none()).unwrap();
        assert_eq!(
            (p.estimator.indirect, p.origin(Param::Epsilon)),
            (Indirect::Epsilon(0.0), Origin::SceneFile(path.into()))
        );
        let both = Overrides { epsilon: Some(0.1), bounces: Some(Bounces::Fixed(1)), ..Default::default() };
        let e = resolve(none(), both.clone()).unwrap_err().to_string();
        assert!(e.starts_with("--bounces 1 cannot be combined with --epsilon 0.1"), "{e}");
        let e = resolve(both, none()).unwrap_err().to_string();
        assert!(
            e.starts_with("s.toml: [render] bounces 1 cannot be combined with s.toml: [render] epsilon 0.1"),
            "{e}"
        );
        assert_eq!(Indirect::Bounces(Bounces::Fixed(0)).bounces(), None);
        assert_eq!(Indirect::Epsilon(0.2).bounces(), None);
        assert_eq!(Indirect::Epsilon(0.2).paper_epsilon(), 0.2);
        assert_eq!(DEFAULT_INDIRECT.paper_epsilon(), DEFAULT_EPSILON);
    }

    #[test]
    fn bounces_read_as_a_count_or_auto() {
        assert_eq!("auto".parse(), Ok(Bounces::Converged));
        assert_eq!("3".parse(), Ok(Bounces::Fixed(3)));
        assert!("-1".parse::<Bounces>().unwrap_err().contains("expected a count of bounces"));
        for (text, expected) in [("bounces = 4", Bounces::Fixed(4)), ("bounces = \"auto\"", Bounces::Converged)] {
            let table: toml::Table = toml::from_str(text).unwrap();
            assert_eq!(Overrides::from_scene_table(Path::new("s.toml"), &table).unwrap().bounces, Some(expected));
        }
        let table: toml::Table = toml::from_str("bounces = \"many\"").unwrap();
        assert!(Overrides::from_scene_table(Path::new("s.toml"), &table).is_err());
    }

    #[test]
    fn a_bad_value_is_named_as_a_flag_or_as_a_render_key() {
        let bad = [
            (Overrides { epsilon: Some(-0.1), ..Default::default() }, Param::Epsilon),
            (Overrides { tile: Some(12), ..Default::default() }, Param::Tile),
            (Overrides { sensor_size: Some(0), ..Default::default() }, Param::SensorSize),
            (Overrides { sensor: Some(SensorShape::Frustum), fov_deg: Some(180.0), ..Default::default() }, Param::Fov),
            (Overrides { dradiance: Some(f32::NAN), ..Default::default() }, Param::Dradiance),
            (Overrides { sensor_size: Some(15), ..Default::default() }, Param::SensorSize),
            (Overrides { filter_radius: Some(MAX_FILTER_RADIUS + 1), ..Default::default() }, Param::FilterRadius),
            (Overrides { cache_resolution: Some(0), ..Default::default() }, Param::CacheResolution),
            (
                Overrides { cache_resolution: Some(MAX_CACHE_RESOLUTION + 1), ..Default::default() },
                Param::CacheResolution,
            ),
        ];
        for (values, param) in bad {
            let as_flag = RenderParams::resolve(None, &values).unwrap_err();
            assert_eq!(as_flag.param, param);
            assert!(as_flag.to_string().starts_with(param.flag()), "{as_flag}");
            let path = Path::new("dir/scene.toml");
            let in_file = RenderParams::resolve(Some((path, &values)), &Overrides::default()).unwrap_err();
            let expected = format!("dir/scene.toml: [render] {} ", param.key());
            assert!(in_file.to_string().starts_with(&expected), "{in_file}");
        }
    }

    #[test]
    fn the_render_table_is_typed_and_unknown_keys_are_refused() {
        let table: toml::Table = toml::from_str("sensor = \"frustum\"\nfov_deg = 90\ntile = 8").unwrap();
        let o = Overrides::from_scene_table(Path::new("s.toml"), &table).unwrap();
        assert_eq!((o.sensor, o.fov_deg, o.tile), (Some(SensorShape::Frustum), Some(90.0), Some(8)));
        for bad in ["samples = 4", "sensor = \"fisheye\"", "tile = \"eight\""] {
            let table: toml::Table = toml::from_str(bad).unwrap();
            let e = Overrides::from_scene_table(Path::new("s.toml"), &table).unwrap_err().to_string();
            assert!(e.starts_with("s.toml: [render]: "), "{e}");
        }
    }

    /// A field of view given to hemicubes, and an ε brighter than every emitter, are warned about, named as
    /// the user set them; the defaults and a frustum's field of view are not.
    #[test]
    fn valid_but_doubtful_values_are_warned_about() {
        let quiet = RenderParams::resolve(None, &Overrides::default()).unwrap();
        assert!(quiet.warnings(17.0).is_empty(), "{:?}", quiet.warnings(17.0));
        let frustum = Overrides { sensor: Some(SensorShape::Frustum), fov_deg: Some(90.0), ..Default::default() };
        assert!(RenderParams::resolve(None, &frustum).unwrap().warnings(17.0).is_empty());
        let hemicube = Overrides { fov_deg: Some(90.0), epsilon: Some(1e9), ..Default::default() };
        let warnings = RenderParams::resolve(None, &hemicube).unwrap().warnings(17.0);
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(warnings[0].starts_with("--fov: ignored by hemicube sensors"), "{warnings:?}");
        assert!(warnings[1].starts_with("--epsilon 1000000000 is brighter than every emitter"), "{warnings:?}");
        let path = Path::new("s.toml");
        let in_file = RenderParams::resolve(Some((path, &hemicube)), &Overrides::default()).unwrap();
        assert!(
            in_file.warnings(17.0)[0].starts_with("s.toml: [render] fov_deg: ignored"),
            "{:?}",
            in_file.warnings(17.0)
        );
        assert_eq!(in_file.warnings(2e9).len(), 1, "an ε below the brightest emitter is fine");
    }
}
