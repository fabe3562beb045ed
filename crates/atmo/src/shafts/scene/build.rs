//! The file's values checked into the renderers' types, with messages naming the field
//! and its allowed range: camera, haze, spotlights, moving heads and their cues.

use super::*;

/// A light's colour from at most one of `color` (linear RGB), `cmy` (0-1 each; the
/// colour is `1 - cmy`; only where `has_cmy`, the light having that key) and `kelvin`,
/// checked; `None` when none is given.
pub(super) fn colour(
    at: &str,
    color: Option<[f32; 3]>,
    (has_cmy, cmy): (bool, Option<[f32; 3]>),
    kelvin: Option<f32>,
) -> Result<Option<Vec3>> {
    let checked = |key: &str, v: [f32; 3], max: f64| -> Result<Vec3> {
        for (c, x) in v.iter().enumerate() {
            check_range(&format!("{at}.{key}[{c}]"), *x as f64, 0.0, max)?;
        }
        Ok(Vec3::from(v))
    };
    Ok(match (color, cmy, kelvin) {
        (None, None, None) => None,
        (Some(rgb), None, None) => Some(checked("color", rgb, 1e6)?),
        (None, Some(cmy), None) => Some(Vec3::ONE - checked("cmy", cmy, 1.0)?),
        (None, None, Some(k)) => {
            check_range(&format!("{at}.kelvin"), k as f64, 1000.0, 40000.0)?;
            Some(kelvin_colour(k))
        }
        _ if !has_cmy => {
            return Err(Error::Invalid(format!(
                "{at}: give at most one of `color` (linear RGB) and `kelvin`"
            )))
        }
        _ => {
            return Err(Error::Invalid(format!(
                "{at}: give at most one of `color` (linear RGB), `cmy` and `kelvin`"
            )))
        }
    })
}

/// The colour of a black body at `kelvin`, normalised to luminance 1, linear sRGB.
pub(super) fn kelvin_colour(kelvin: f32) -> Vec3 {
    Vec3::from(blackbody_srgb(kelvin as f64).map(|c| c as f32))
}

/// Refuses the keys of `given` that are set: `why` says where their values come from.
pub(super) fn refuse_given(at: &str, given: &[(&str, bool)], why: &str) -> Result<()> {
    match given.iter().find(|(_, set)| *set) {
        Some((key, _)) => Err(Error::Invalid(format!(
            "{at}.{key}: {why}; leave `{key}` out"
        ))),
        None => Ok(()),
    }
}

pub(super) fn vec3(field: &str, v: [f32; 3]) -> Result<Vec3> {
    let v = Vec3::from(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::out_of_range(
            field,
            format!("{v:?}"),
            "finite numbers",
        ))
    }
}

pub(super) fn unit_vector(field: &str, v: [f32; 3]) -> Result<Vec3> {
    vec3(field, v)?
        .try_normalize()
        .ok_or_else(|| Error::out_of_range(field, format!("{v:?}"), "a non-zero vector"))
}

pub(super) fn albedo(field: &str, a: AlbedoSpec) -> Result<Vec3> {
    let rgb = match a {
        AlbedoSpec::Grey(g) => [g; 3],
        AlbedoSpec::Rgb(rgb) => rgb,
    };
    for (c, v) in rgb.iter().enumerate() {
        check_range(&format!("{field}[{c}]"), *v as f64, 0.0, 1.0)?;
    }
    Ok(Vec3::from(rgb))
}

impl CameraSpec {
    pub(super) fn validate(&self) -> Result<Camera> {
        let position = vec3("camera.position", self.position)?;
        let look_at = vec3("camera.look_at", self.look_at)?;
        let up = vec3("camera.up", self.up)?;
        let fov = match self.fov_axis {
            FovAxis::Vertical => Fov::Vertical(self.fov_deg),
            FovAxis::Horizontal => Fov::Horizontal(self.fov_deg),
        };
        Camera::look_at(position, look_at, up, fov, (self.width, self.height))?
            .with_supersampling(self.supersampling)?
            .with_far(self.far_m)
    }
}

impl HazeSpec {
    pub(super) fn validate(&self) -> Result<Haze> {
        check_positive("haze.extinction", self.extinction as f64, 100.0)?;
        check_range("haze.albedo", self.albedo as f64, 0.0, 1.0)?;
        let phase = match self.phase {
            PhaseSpec::Paper { exponent } => {
                check_range("haze.phase.exponent", exponent as f64, 0.0, 1000.0)?;
                PhaseFunction::PaperHaze {
                    exponent: exponent as f64,
                }
            }
            PhaseSpec::HenyeyGreenstein { g } => {
                check_range("haze.phase.g", g as f64, -0.99, 0.99)?;
                PhaseFunction::HenyeyGreenstein { g: g as f64 }
            }
        };
        let bounds = match &self.bounds {
            None => None,
            Some(b) => {
                let (min, max) = (vec3("haze.box.min", b.min)?, vec3("haze.box.max", b.max)?);
                if !min.cmplt(max).all() {
                    return Err(Error::out_of_range(
                        "haze.box.max",
                        format!("{max:?}"),
                        &format!("greater than haze.box.min = {min:?} on every axis"),
                    ));
                }
                Some(Aabb { min, max })
            }
        };
        Ok(Haze {
            extinction: self.extinction,
            albedo: self.albedo,
            phase,
            bounds,
        })
    }
}

impl SpotlightSpec {
    pub(super) fn validate(
        &self,
        at: &str,
        unit: IntensityUnit,
        assets: &Assets,
    ) -> Result<Spotlight> {
        let position = vec3(&format!("{at}.position"), self.position)?;
        let axis = match (self.aim, self.direction) {
            (Some(aim), None) => {
                let aim = vec3(&format!("{at}.aim"), aim)?;
                (aim - position).try_normalize().ok_or_else(|| {
                    Error::Invalid(format!(
                        "{at}.aim equals {at}.position: the light has no axis"
                    ))
                })?
            }
            (None, Some(d)) => unit_vector(&format!("{at}.direction"), d)?,
            _ => {
                return Err(Error::Invalid(format!(
                    "{at}: give exactly one of `aim` (a point) and `direction` (a vector)"
                )))
            }
        };
        // The light's up: the given one, else world y (z for a beam along y).
        let up = match self.up {
            Some(up) => unit_vector(&format!("{at}.up"), up)?,
            None if axis.y.abs() > 0.999 => Vec3::Z,
            None => Vec3::Y,
        };
        let light_from_world = light_frame(axis, up)
            .ok_or_else(|| Error::Invalid(format!("{at}.up is parallel to the beam axis")))?;
        let colour = colour(at, self.color, (false, None), self.kelvin)?.unwrap_or(Vec3::ONE);
        check_range(&format!("{at}.dimmer"), self.dimmer as f64, 0.0, 1.0)?;
        if self.intensity_unit != unit {
            return Err(Error::Invalid(format!(
                "{at}.intensity_unit differs from spotlight[0]'s: all lights of a scene share one unit"
            )));
        }
        let (intensity, field_half, profile) = match &self.profile {
            None => self.beam(at)?,
            Some(spec) => self.measured(at, spec, assets)?,
        };
        let gobo = match &self.gobo {
            None => None,
            Some(file) => Some(assets.gobo(file, self.gobo_sampling.into())?),
        };
        Ok(Spotlight::new(
            position,
            light_from_world,
            colour * (self.dimmer * intensity),
            field_half,
            profile,
            gobo,
        ))
    }

    /// A beam and field light: its intensity, half field angle (rad) and profile.
    pub(super) fn beam(&self, at: &str) -> Result<(f32, f32, Profile)> {
        let need = |value: Option<f32>, key: &str| {
            value.ok_or_else(|| {
                Error::Invalid(format!(
                    "{at}: `{key}` is missing (a light needs `intensity`, `beam_deg` and \
                     `field_deg`, or a measured `profile`)"
                ))
            })
        };
        let intensity = need(self.intensity, "intensity")?;
        let (beam_deg, field_deg) = (
            need(self.beam_deg, "beam_deg")?,
            need(self.field_deg, "field_deg")?,
        );
        check_positive(&format!("{at}.intensity"), intensity as f64, 1e9)?;
        check_range(&format!("{at}.field_deg"), field_deg as f64, 0.1, 170.0)?;
        check_range(
            &format!("{at}.beam_deg"),
            beam_deg as f64,
            0.0,
            field_deg as f64,
        )?;
        let falloff = self.falloff.unwrap_or_default().into();
        Ok((
            intensity,
            0.5 * field_deg.to_radians(),
            Profile::Beam {
                beam_half: 0.5 * beam_deg.to_radians(),
                falloff,
            },
        ))
    }

    /// A light with a measured profile: its peak candela, half field angle (rad: where
    /// the file's light ends, at most [`MEASURED_REACH_DEG`]) and profile.
    pub(super) fn measured(
        &self,
        at: &str,
        spec: &ProfileSpec,
        assets: &Assets,
    ) -> Result<(f32, f32, Profile)> {
        refuse_given(
            at,
            &[
                ("intensity", self.intensity.is_some()),
                ("beam_deg", self.beam_deg.is_some()),
                ("field_deg", self.field_deg.is_some()),
                ("falloff", self.falloff.is_some()),
            ],
            "a light with a measured `profile` takes its intensity and angles from the \
             file (`dimmer` scales it)",
        )?;
        if self.intensity_unit != IntensityUnit::Candela {
            return Err(Error::Invalid(format!(
                "{at}.intensity_unit: a photometric file gives candela; the scene's unit must be \"cd\""
            )));
        }
        let (file, eulumdat) = spec.file(at)?;
        let photometry = assets.profile(file, eulumdat)?;
        let reach = photometry.reach().min(MEASURED_REACH_DEG);
        Ok((
            photometry.peak(),
            reach.to_radians(),
            Profile::Measured(photometry),
        ))
    }
}

/// The scene's moving heads and cues, validated: ranges, names, gobo slots, cue order.
pub(super) fn show(spec: &SceneSpec, unit: IntensityUnit, assets: &Assets) -> Result<Show> {
    let (fixtures, limits): (Vec<Fixture>, Vec<Limits>) = spec
        .fixture
        .iter()
        .enumerate()
        .map(|(i, f)| f.validate(&format!("fixture[{i}] ({})", f.name), unit, assets))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    for (i, f) in fixtures.iter().enumerate() {
        if fixtures[..i].iter().any(|g| g.name == f.name) {
            return Err(Error::Invalid(format!(
                "fixture[{i}].name = {:?} is used twice: cues name fixtures, so names must differ",
                f.name
            )));
        }
    }
    let mut cues = Vec::with_capacity(spec.cue.len());
    for (i, c) in spec.cue.iter().enumerate() {
        let at = format!("cue[{i}]");
        check_range(&format!("{at}.time_s"), c.time_s as f64, 0.0, 1e6)?;
        check_range(&format!("{at}.fade_s"), c.fade_s as f64, 0.0, 1e6)?;
        if let Some(before) = spec.cue[..i].last() {
            if c.time_s < before.time_s {
                return Err(Error::out_of_range(
                    &format!("{at}.time_s"),
                    c.time_s,
                    &format!(
                        "at least cue[{}].time_s = {}: cues in time order",
                        i - 1,
                        before.time_s
                    ),
                ));
            }
        }
        let changes = c
            .set
            .iter()
            .map(|(name, attributes)| {
                let k = fixtures
                    .iter()
                    .position(|f| &f.name == name)
                    .ok_or_else(|| {
                        Error::Invalid(format!(
                            "{at}.set.{name}: no fixture is named {name:?} (fixtures: {})",
                            fixtures
                                .iter()
                                .map(|f| f.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ))
                    })?;
                let change = attributes.validate(&format!("{at}.set.{name}"), &limits[k])?;
                Ok((k, change))
            })
            .collect::<Result<Vec<_>>>()?;
        cues.push(Cue {
            time_s: c.time_s,
            fade_s: c.fade_s,
            changes,
        });
    }
    Ok(Show::new(fixtures, cues))
}

impl FixtureSpec {
    pub(super) fn validate(
        &self,
        at: &str,
        unit: IntensityUnit,
        assets: &Assets,
    ) -> Result<(Fixture, Limits)> {
        let field = |name: &str| format!("{at}.{name}");
        let position = vec3(&field("position"), self.position)?;
        let axis = unit_vector(&field("axis"), self.axis)?;
        let front = vec3(&field("front"), self.front)?;
        let front = (front - axis * front.dot(axis))
            .try_normalize()
            .ok_or_else(|| Error::Invalid(format!("{at}.front is parallel to its axis")))?;
        check_range(
            &field("gobo_rotation_deg"),
            self.gobo_rotation_deg as f64,
            -360.0,
            360.0,
        )?;
        let sampling = self.gobo_sampling.into();
        let mut light = match &self.gdtf {
            None => self.keyed(at, assets, sampling)?,
            Some(file) => self.gdtf_light(at, unit, assets, file, sampling)?,
        };
        // A prism the scene gives is in the beam at rest; a GDTF file's is out, as a
        // desk's prism channel at its default (the wheel's open slot).
        let (prism, prism_at_rest) = match self.prism {
            Some(p) => (Some(p.validate(&field("prism"))?), true),
            None => (light.prism, false),
        };
        light.limits.prism = prism.is_some();
        let limits = &light.limits;
        for (name, [lo, hi], limit) in [
            ("pan_range_deg", limits.pan, 720.0),
            ("tilt_range_deg", limits.tilt, 360.0),
        ] {
            check_range(&format!("{}[0]", field(name)), lo as f64, -limit, limit)?;
            check_range(&format!("{}[1]", field(name)), hi as f64, lo as f64, limit)?;
        }
        let [narrow, wide] = limits.zoom;
        check_range(
            &format!("{}[1]", field("zoom_range_deg")),
            wide as f64,
            0.5,
            120.0,
        )?;
        check_range(
            &format!("{}[0]", field("zoom_range_deg")),
            narrow as f64,
            0.5,
            wide as f64,
        )?;
        check_range(&field("field_ratio"), light.field_ratio as f64, 1.0, 3.0)?;
        check_positive(&field("intensity"), light.intensity as f64, 1e9)?;
        // At rest: pan and tilt 0 (or the nearest the ranges allow), widest, open,
        // full, the file's colour temperature or white.
        let white = light.kelvin.map_or(Vec3::ONE, kelvin_colour);
        let rest = State {
            channels: [
                0f32.clamp(limits.pan[0], limits.pan[1]),
                0f32.clamp(limits.tilt[0], limits.tilt[1]),
                wide,
                1.0,
                1.0,
                white.x,
                white.y,
                white.z,
                0.0,
                0.0,
            ],
            gobo: 0,
            prism_in: prism_at_rest,
        };
        let change = self.start.validate(&format!("{at}.start"), limits)?;
        let start = State {
            channels: std::array::from_fn(|c| change.channels[c].unwrap_or(rest.channels[c])),
            gobo: change.gobo.unwrap_or(0),
            prism_in: change.prism_in.unwrap_or(rest.prism_in),
        };
        let patch = self
            .dmx
            .as_ref()
            .map(|d| d.patch(&field("dmx"), &light))
            .transpose()?;
        let fixture = Fixture {
            white,
            patch,
            body: self.body,
            #[cfg(feature = "gdtf")]
            model: light.body.take().map(std::sync::Arc::new),
            name: self.name.clone(),
            position,
            axis,
            front,
            intensity: light.intensity,
            zoom_range_deg: limits.zoom,
            zoom_scale: light.zoom_scale,
            field_ratio: light.field_ratio,
            falloff: self.falloff.into(),
            wheel: light.wheel,
            gobo_rotation_deg: self.gobo_rotation_deg,
            pan_range_deg: limits.pan,
            tilt_range_deg: limits.tilt,
            start,
            prism,
        };
        Ok((fixture, light.limits))
    }

    /// The light as the fixture's own keys give it.
    pub(super) fn keyed(&self, at: &str, assets: &Assets, sampling: Sampling) -> Result<Light> {
        if self.mode.is_some() {
            return Err(Error::Invalid(format!(
                "{at}.mode names a DMX mode of a GDTF file; give `gdtf` with it"
            )));
        }
        let intensity = self.intensity.ok_or_else(|| {
            Error::Invalid(format!(
                "{at}: `intensity` is missing (or give a `gdtf` file, which has it)"
            ))
        })?;
        let wheel = self
            .gobo_wheel
            .iter()
            .flatten()
            .map(|file| assets.gobo(file, sampling))
            .collect::<Result<Vec<_>>>()?;
        Ok(Light {
            intensity,
            zoom_scale: 1.0,
            field_ratio: self.field_ratio.unwrap_or(DEFAULT_FIELD_RATIO),
            limits: Limits {
                pan: self.pan_range_deg.unwrap_or(DEFAULT_PAN),
                tilt: self.tilt_range_deg.unwrap_or(DEFAULT_TILT),
                zoom: self.zoom_range_deg.unwrap_or(DEFAULT_ZOOM),
                slots: wheel.len(),
                prism: false,
            },
            wheel,
            kelvin: None,
            prism: None,
            dmx_mode: None,
            #[cfg(feature = "gdtf")]
            body: None,
        })
    }

    /// The light as the GDTF file `file` gives it in the fixture's `mode`: GDTF's beam
    /// and field angles (half and a tenth of the peak) turned into atmo's smooth edge,
    /// the intensity from the beam's luminous flux spread over that profile at the
    /// widest zoom.
    pub(super) fn gdtf_light(
        &self,
        at: &str,
        unit: IntensityUnit,
        assets: &Assets,
        file: &Path,
        sampling: Sampling,
    ) -> Result<Light> {
        refuse_given(
            at,
            &[
                ("intensity", self.intensity.is_some()),
                ("pan_range_deg", self.pan_range_deg.is_some()),
                ("tilt_range_deg", self.tilt_range_deg.is_some()),
                ("zoom_range_deg", self.zoom_range_deg.is_some()),
                ("field_ratio", self.field_ratio.is_some()),
                ("gobo_wheel", self.gobo_wheel.is_some()),
            ],
            "a fixture from a GDTF file takes it from the file",
        )?;
        if unit != IntensityUnit::Candela {
            return Err(Error::Invalid(format!(
                "{at}.gdtf: a GDTF beam gives lumens, so the scene's unit must be \"cd\""
            )));
        }
        let mode = self.mode.as_deref().ok_or_else(|| {
            Error::Invalid(format!(
                "{at}: `mode` is missing: the GDTF file's DMX mode to use"
            ))
        })?;
        let path = assets.path(file);
        let file = assets.fixture(file, mode, sampling)?;
        // The file's prism, unless the scene gives the fixture its own.
        let prism = match (&file.prism, self.prism) {
            (Some(p), None) => Some(p.circular().map_err(|why| {
                Error::Invalid(format!("{at}.gdtf: GDTF file {}: {why}", path.display()))
            })?),
            _ => None,
        };
        let (beam, field) = gdtf::to_smooth_edge(file.beam_deg, file.field_deg);
        // atmo's beam at least a third of its field (the field ratio's limit).
        let beam = beam.max(field / 3.0).max(0.5);
        let field_ratio = (field / beam).max(1.0);
        // The zoom stays in the file's terms (its half-intensity beam angle).
        let zoom_scale = beam / file.beam_deg.max(1e-3);
        let zoom = file.zoom_range_deg.unwrap_or([file.beam_deg; 2]);
        let widest = zoom[1] * zoom_scale;
        let intensity = file.luminous_flux_lm
            / profile_solid_angle(
                0.5 * widest.to_radians(),
                (0.5 * widest * field_ratio)
                    .min(MEASURED_REACH_DEG)
                    .to_radians(),
                self.falloff.into(),
            );
        Ok(Light {
            intensity,
            zoom_scale,
            field_ratio,
            limits: Limits {
                pan: file.pan_range_deg.unwrap_or([0.0, 0.0]),
                tilt: file.tilt_range_deg.unwrap_or([0.0, 0.0]),
                zoom,
                slots: file.wheel.len(),
                prism: false,
            },
            wheel: file.wheel,
            kelvin: Some(file.kelvin),
            prism,
            dmx_mode: Some(file.dmx),
            #[cfg(feature = "gdtf")]
            body: Some(file.body).filter(|b| !b.is_empty()),
        })
    }
}

impl DmxSpec {
    /// The patch: the GDTF file's mode, or the personality of `channels` over the
    /// fixture's ranges; the footprint within the universe.
    pub(super) fn patch(&self, at: &str, light: &Light) -> Result<dmx::Patch> {
        let mode = match (&light.dmx_mode, &self.channels) {
            (Some(mode), None) => mode.clone(),
            (None, Some(names)) => {
                let l = &light.limits;
                dmx::Mode::personality(names, [l.pan, l.tilt, l.zoom], l.slots, at)?
            }
            (Some(_), Some(_)) => {
                return Err(Error::Invalid(format!(
                    "{at}.channels: a GDTF fixture's channels are its mode's; leave them out"
                )))
            }
            (None, None) => {
                return Err(Error::Invalid(format!(
                    "{at}.channels is missing: a fixture without a GDTF file needs its \
                     personality, as [\"pan\", \"pan_fine\", \"tilt\", \"dimmer\"] ({})",
                    dmx::PERSONALITY.join(", ")
                )))
            }
        };
        check_range(
            &format!("{at}.universe"),
            self.universe as f64,
            1.0,
            63999.0,
        )?;
        check_range(&format!("{at}.address"), self.address as f64, 1.0, 512.0)?;
        dmx::Patch::new(self.universe as u16, self.address as u16, mode, at)
    }
}

/// A GDTF file's fixture in `mode`.
#[cfg(feature = "gdtf")]
pub(super) fn read_gdtf(path: &Path, mode: &str, sampling: Sampling) -> Result<gdtf::GdtfFixture> {
    let bytes = crate::files::read_bounded(path, "GDTF file", crate::files::DATA_LIMIT_BYTES)?;
    gdtf::read(&bytes, &path.display().to_string(), mode, sampling)
}

/// Without atmo's `gdtf` feature, GDTF files are refused with a message saying so.
#[cfg(not(feature = "gdtf"))]
pub(super) fn read_gdtf(
    path: &Path,
    _mode: &str,
    _sampling: Sampling,
) -> Result<gdtf::GdtfFixture> {
    Err(Error::Invalid(format!(
        "GDTF file {}: fixtures from GDTF files need atmo's `gdtf` feature, which this build leaves out",
        path.display()
    )))
}

impl AttributesSpec {
    /// The change these attributes make on a fixture of `limits`, each checked
    /// against its range.
    pub(super) fn validate(&self, at: &str, limits: &Limits) -> Result<Change> {
        let mut change = Change::default();
        // The fading attributes that are numbers: channel, value and range, checked in
        // this order (the colour between the dimmer and the gobo's speed).
        let numbers = [
            (0, self.pan_deg, limits.pan),
            (1, self.tilt_deg, limits.tilt),
            (2, self.zoom_deg, limits.zoom),
            (3, self.iris, [0.05, 1.0]),
            (4, self.dimmer, [0.0, 1.0]),
            (8, self.gobo_speed_dps, [-3600.0, 3600.0]),
            (9, self.prism_deg, [-3600.0, 3600.0]),
        ];
        let mut set = |list: &[(usize, Option<f32>, [f32; 2])]| {
            for &(c, value, [lo, hi]) in list {
                if let Some(v) = value {
                    check_range(
                        &format!("{at}.{}", CHANNELS[c]),
                        v as f64,
                        lo as f64,
                        hi as f64,
                    )?;
                    change.channels[c] = Some(v);
                }
            }
            Ok::<(), Error>(())
        };
        set(&numbers[..5])?;
        let colour = colour(at, self.color, (true, self.cmy), self.kelvin)?;
        set(&numbers[5..])?;
        if let Some(rgb) = colour {
            for c in 0..3 {
                change.channels[5 + c] = Some(rgb[c]);
            }
        }
        if let Some(slot) = self.gobo {
            let slots = limits.slots;
            if slot > slots {
                return Err(Error::out_of_range(
                    &format!("{at}.gobo"),
                    slot,
                    &format!("0 (open) to {slots} (the gobo_wheel's images)"),
                ));
            }
            change.gobo = Some(slot);
        }
        if let Some(prism_in) = self.prism_in {
            if !limits.prism {
                return Err(Error::Invalid(format!(
                    "{at}.prism_in: the fixture has no prism to put in or take out (give it \
                     `prism = {{ facets = 3, angle_deg = 9.0 }}`)"
                )));
            }
            change.prism_in = Some(prism_in);
        }
        Ok(change)
    }
}
