//! The scene file's format: plain `Deserialize` structs with `deny_unknown_fields`,
//! one per table of the file, and their defaults (docs/shafts.md gives every key).

use super::*;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneSpec {
    pub(super) camera: CameraSpec,
    pub(super) haze: HazeSpec,
    #[serde(default)]
    pub(super) render: RenderSpec,
    #[serde(default)]
    pub(super) display: DisplaySpec,
    #[serde(default)]
    pub(super) spotlight: Vec<SpotlightSpec>,
    #[serde(default)]
    pub(super) object: Vec<ObjectSpec>,
    #[serde(default)]
    pub(super) fixture: Vec<FixtureSpec>,
    #[serde(default)]
    pub(super) cue: Vec<CueSpec>,
    /// A rig from an MVR file: its fixtures after `fixture`'s, its truss and scenery
    /// among the objects.
    pub(super) mvr: Option<MvrSpec>,
}

/// `[mvr]`: the MVR file and what to make of it (docs/previz.md).
#[derive(Deserialize)]
#[cfg_attr(not(feature = "gdtf"), allow(dead_code))]
#[serde(deny_unknown_fields)]
pub(super) struct MvrSpec {
    pub(super) file: PathBuf,
    /// GDTF files that stand in for the MVR's own, by the name the MVR gives them.
    #[serde(default)]
    pub(super) replace: Vec<ReplaceSpec>,
    /// Draw fixtures whose GDTF atmo cannot light (no beam, no such mode) dark, instead
    /// of refusing the rig.
    #[serde(default)]
    pub(super) keep_dark: bool,
    /// The truss's and the scenery's albedo.
    #[serde(default = "truss_albedo")]
    pub(super) albedo: f32,
    /// Whether the fixtures' bodies are drawn.
    #[serde(default = "yes")]
    pub(super) bodies: bool,
}

fn truss_albedo() -> f32 {
    0.35
}

/// A GDTF file and mode for the MVR's fixtures of type `spec`.
#[derive(Deserialize)]
#[cfg_attr(not(feature = "gdtf"), allow(dead_code))]
#[serde(deny_unknown_fields)]
pub(super) struct ReplaceSpec {
    pub(super) spec: String,
    pub(super) gdtf: PathBuf,
    pub(super) mode: String,
}

/// A moving head ([`super::show::Fixture`]); angles in degrees. With `gdtf` the file
/// gives the intensity, the ranges, the field ratio and the gobo wheel.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FixtureSpec {
    pub(super) name: String,
    pub(super) position: [f32; 3],
    #[serde(default = "down")]
    pub(super) axis: [f32; 3],
    #[serde(default = "z_front")]
    pub(super) front: [f32; 3],
    pub(super) gdtf: Option<PathBuf>,
    pub(super) mode: Option<String>,
    pub(super) intensity: Option<f32>,
    pub(super) pan_range_deg: Option<[f32; 2]>,
    pub(super) tilt_range_deg: Option<[f32; 2]>,
    pub(super) zoom_range_deg: Option<[f32; 2]>,
    pub(super) field_ratio: Option<f32>,
    #[serde(default)]
    pub(super) falloff: FalloffSpec,
    pub(super) gobo_wheel: Option<Vec<PathBuf>>,
    #[serde(default)]
    pub(super) gobo_sampling: SamplingSpec,
    #[serde(default)]
    pub(super) gobo_rotation_deg: f32,
    /// The attributes at the show's start (the rest at rest: along the axis, widest,
    /// open, full, white, no gobo).
    #[serde(default)]
    pub(super) start: AttributesSpec,
    /// A prism in the beam: `{ facets = 3, angle_deg = 8 }` (its turn is the
    /// `prism_deg` attribute).
    pub(super) prism: Option<PrismSpec>,
    /// Where a desk drives it: `{ universe = 1, address = 1 }`, and for a fixture
    /// without a GDTF file its personality's `channels`.
    pub(super) dmx: Option<DmxSpec>,
    /// Whether its body (base, yoke, head) is drawn; default true.
    #[serde(default = "yes")]
    pub(super) body: bool,
}

pub(super) fn yes() -> bool {
    true
}

/// A fixture's DMX patch, as the scene gives it ([`crate::shafts::dmx::Patch`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DmxSpec {
    #[serde(default = "first_universe")]
    pub(super) universe: u32,
    pub(super) address: u32,
    /// The personality's channel names, in order ([`crate::shafts::dmx::PERSONALITY`]).
    pub(super) channels: Option<Vec<String>>,
}

fn first_universe() -> u32 {
    1
}

/// A fixture's prism, as the scene gives it (see [`Prism`]).
#[derive(Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub(super) struct PrismSpec {
    pub(super) facets: u32,
    pub(super) angle_deg: f32,
}

impl PrismSpec {
    /// The prism, every number in its range ([`Prism::FACETS`], each beam at most
    /// [`Prism::MAX_ANGLE_DEG`] off the head's).
    pub(super) fn validate(&self, at: &str) -> Result<Prism> {
        let [fewest, most] = Prism::FACETS.map(f64::from);
        check_range(&format!("{at}.facets"), self.facets as f64, fewest, most)?;
        let most_deg = Prism::MAX_ANGLE_DEG as f64;
        check_range(
            &format!("{at}.angle_deg"),
            self.angle_deg as f64,
            0.0,
            most_deg,
        )?;
        Ok(Prism {
            facets: self.facets,
            angle_deg: self.angle_deg,
        })
    }
}

/// What a fixture's attributes may be: pan, tilt and zoom ranges (degrees) and the
/// gobo wheel's slots.
pub(super) struct Limits {
    pub(super) pan: [f32; 2],
    pub(super) tilt: [f32; 2],
    pub(super) zoom: [f32; 2],
    pub(super) slots: usize,
    /// Whether the head has a prism to put in and take out.
    pub(super) prism: bool,
}

/// A fixture's light as its keys or its GDTF file give it.
pub(super) struct Light {
    pub(super) intensity: f32,
    pub(super) zoom_scale: f32,
    pub(super) field_ratio: f32,
    pub(super) wheel: Vec<Gobo>,
    pub(super) kelvin: Option<f32>,
    /// The prism a GDTF file gives (keys give theirs with `prism`).
    pub(super) prism: Option<Prism>,
    pub(super) limits: Limits,
    /// The DMX mode a GDTF file gives.
    pub(super) dmx_mode: Option<crate::shafts::dmx::Mode>,
    /// The body a GDTF file's models draw, if it has any.
    #[cfg(feature = "gdtf")]
    pub(super) body: Option<crate::shafts::gdtf_body::GdtfBody>,
}

pub(super) fn down() -> [f32; 3] {
    [0.0, -1.0, 0.0]
}
pub(super) fn z_front() -> [f32; 3] {
    [0.0, 0.0, 1.0]
}
/// A fixture's ranges and field ratio where neither its keys nor a file give them.
pub(super) const DEFAULT_PAN: [f32; 2] = [-270.0, 270.0];
pub(super) const DEFAULT_TILT: [f32; 2] = [-135.0, 135.0];
pub(super) const DEFAULT_ZOOM: [f32; 2] = [10.0, 40.0];
pub(super) const DEFAULT_FIELD_RATIO: f32 = 1.3;

/// A fixture's attributes, as set at the start or by a cue; absent ones unchanged.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct AttributesSpec {
    pub(super) pan_deg: Option<f32>,
    pub(super) tilt_deg: Option<f32>,
    pub(super) zoom_deg: Option<f32>,
    pub(super) iris: Option<f32>,
    pub(super) dimmer: Option<f32>,
    pub(super) color: Option<[f32; 3]>,
    pub(super) cmy: Option<[f32; 3]>,
    pub(super) kelvin: Option<f32>,
    pub(super) gobo: Option<usize>,
    pub(super) gobo_speed_dps: Option<f32>,
    pub(super) prism_deg: Option<f32>,
    pub(super) prism_in: Option<bool>,
}

/// A cue: at `time_s`, the attributes it sets per fixture fade over `fade_s`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CueSpec {
    pub(super) time_s: f32,
    #[serde(default)]
    pub(super) fade_s: f32,
    #[serde(default)]
    pub(super) set: std::collections::BTreeMap<String, AttributesSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSpec {
    pub(super) position: [f32; 3],
    pub(super) look_at: [f32; 3],
    #[serde(default = "y_up")]
    pub(super) up: [f32; 3],
    pub(super) fov_deg: f32,
    #[serde(default)]
    pub(super) fov_axis: FovAxis,
    pub(super) width: u32,
    pub(super) height: u32,
    #[serde(default = "one")]
    pub(super) supersampling: u32,
    #[serde(default = "default_far")]
    pub(super) far_m: f32,
}

pub(super) fn y_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
pub(super) fn one() -> u32 {
    1
}
pub(super) fn default_far() -> f32 {
    1000.0
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(super) enum FovAxis {
    #[default]
    Vertical,
    Horizontal,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct HazeSpec {
    pub(super) extinction: f32,
    #[serde(default = "one_f")]
    pub(super) albedo: f32,
    #[serde(default)]
    pub(super) phase: PhaseSpec,
    #[serde(rename = "box")]
    pub(super) bounds: Option<BoxSpec>,
}

pub(super) fn one_f() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub(super) enum PhaseSpec {
    Paper {
        #[serde(default = "sixteen")]
        exponent: f32,
    },
    HenyeyGreenstein {
        g: f32,
    },
}

pub(super) fn sixteen() -> f32 {
    16.0
}

impl Default for PhaseSpec {
    fn default() -> Self {
        PhaseSpec::Paper { exponent: 16.0 }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoxSpec {
    pub(super) min: [f32; 3],
    pub(super) max: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RenderSpec {
    #[serde(default = "default_planes")]
    pub(super) planes: u32,
    #[serde(default = "default_sub_planes")]
    pub(super) sub_planes: u32,
    #[serde(default = "default_shadow_map")]
    pub(super) shadow_map: u32,
    #[serde(default = "default_adaptive")]
    pub(super) adaptive: bool,
}

pub(super) fn default_planes() -> u32 {
    PlaneSettings::default().planes
}
pub(super) fn default_sub_planes() -> u32 {
    PlaneSettings::default().sub_planes
}
pub(super) fn default_shadow_map() -> u32 {
    PlaneSettings::default().shadow_map
}
pub(super) fn default_adaptive() -> bool {
    PlaneSettings::default().adaptive
}

impl Default for RenderSpec {
    fn default() -> Self {
        RenderSpec {
            planes: default_planes(),
            sub_planes: default_sub_planes(),
            shadow_map: default_shadow_map(),
            adaptive: default_adaptive(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DisplaySpec {
    #[serde(default = "one_f")]
    pub(super) exposure: f32,
    #[serde(default)]
    pub(super) tone_map: ToneMapSpec,
}

impl Default for DisplaySpec {
    fn default() -> Self {
        DisplaySpec {
            exposure: 1.0,
            tone_map: ToneMapSpec::Exponential,
        }
    }
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(super) enum ToneMapSpec {
    #[default]
    Exponential,
    Aces,
    Clamp,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SpotlightSpec {
    pub(super) position: [f32; 3],
    pub(super) aim: Option<[f32; 3]>,
    pub(super) direction: Option<[f32; 3]>,
    pub(super) up: Option<[f32; 3]>,
    pub(super) color: Option<[f32; 3]>,
    pub(super) kelvin: Option<f32>,
    pub(super) intensity: Option<f32>,
    #[serde(default = "one_f")]
    pub(super) dimmer: f32,
    #[serde(default = "candela")]
    pub(super) intensity_unit: IntensityUnit,
    pub(super) beam_deg: Option<f32>,
    pub(super) field_deg: Option<f32>,
    pub(super) falloff: Option<FalloffSpec>,
    pub(super) profile: Option<ProfileSpec>,
    pub(super) gobo: Option<PathBuf>,
    #[serde(default)]
    pub(super) gobo_sampling: SamplingSpec,
}

pub(super) fn candela() -> IntensityUnit {
    IntensityUnit::Candela
}

/// A measured profile: one photometric file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ProfileSpec {
    pub(super) ies: Option<PathBuf>,
    pub(super) ldt: Option<PathBuf>,
}

impl ProfileSpec {
    /// The file and whether it is EULUMDAT.
    pub(super) fn file(&self, at: &str) -> Result<(&Path, bool)> {
        match (&self.ies, &self.ldt) {
            (Some(f), None) => Ok((f, false)),
            (None, Some(f)) => Ok((f, true)),
            _ => Err(Error::Invalid(format!(
                "{at}.profile: give exactly one of `ies` (an IES LM-63 file) and `ldt` (a EULUMDAT file)"
            ))),
        }
    }
}

impl From<FalloffSpec> for Falloff {
    fn from(f: FalloffSpec) -> Falloff {
        match f {
            FalloffSpec::Linear => Falloff::Linear,
            FalloffSpec::Smooth => Falloff::Smooth,
        }
    }
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(super) enum FalloffSpec {
    Linear,
    #[default]
    Smooth,
}

impl From<SamplingSpec> for Sampling {
    fn from(s: SamplingSpec) -> Sampling {
        match s {
            SamplingSpec::Nearest => Sampling::Nearest,
            SamplingSpec::Bilinear => Sampling::Bilinear,
        }
    }
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(super) enum SamplingSpec {
    Nearest,
    #[default]
    Bilinear,
}

/// An albedo: one grey value or linear RGB.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
pub(super) enum AlbedoSpec {
    Grey(f32),
    Rgb([f32; 3]),
}

#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub(super) enum ObjectSpec {
    Plane {
        point: [f32; 3],
        normal: [f32; 3],
        albedo: AlbedoSpec,
    },
    Rect {
        corner: [f32; 3],
        edge_a: [f32; 3],
        edge_b: [f32; 3],
        albedo: AlbedoSpec,
    },
    Sphere {
        center: [f32; 3],
        radius: f32,
        albedo: AlbedoSpec,
    },
    Box {
        min: [f32; 3],
        max: [f32; 3],
        albedo: AlbedoSpec,
    },
    Mesh {
        file: PathBuf,
        #[serde(default = "one_f")]
        scale: f32,
        #[serde(default)]
        rotate_y_deg: f32,
        #[serde(default)]
        translate: [f32; 3],
        albedo: AlbedoSpec,
    },
}
