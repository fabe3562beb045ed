//! The medium: a spherical planet wrapped in air (Rayleigh), aerosols (Mie) and an
//! optional ozone layer, described per wavelength.
//!
//! Parameters come from TOML (`Atmosphere::from_toml_str`) or an embedded preset
//! (`Atmosphere::preset`), are validated once here, and are plain numbers afterwards:
//! per-wavelength coefficients are resolved into one `Vec<f64>` per quantity.

pub mod geometry;
pub mod optical_depth;
pub mod phase;
pub mod spectrum;

use serde::Deserialize;

use crate::error::{check_positive, check_range, Error, Result};
pub use optical_depth::TransmittanceTable;
pub use phase::PhaseFunction;

/// Number of absorbing or scattering constituents whose column densities we track:
/// Rayleigh, Mie, ozone (in this order).
pub const CONSTITUENTS: usize = 3;

/// Names and TOML texts of the embedded presets; the first is the default.
const PRESETS: [(&str, &str); 3] = [
    ("earth", include_str!("../../presets/earth.toml")),
    (
        "earth-spectral",
        include_str!("../../presets/earth-spectral.toml"),
    ),
    ("paper", include_str!("../../presets/paper.toml")),
];

/// A quantity given per wavelength: one value for all, an array with one value per
/// wavelength, or a power law `value * (lambda / at_nm)^(-exponent)`
/// (exponent 4 for Rayleigh, the Angstrom exponent for aerosols).
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum PerWavelength {
    Constant(f64),
    Values(Vec<f64>),
    PowerLaw(PowerLaw),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct PowerLaw {
    at_nm: f64,
    value: f64,
    exponent: f64,
}

impl PerWavelength {
    fn resolve(&self, field: &str, wavelengths_nm: &[f64], max: f64) -> Result<Vec<f64>> {
        let values = match self {
            PerWavelength::Constant(v) => vec![*v; wavelengths_nm.len()],
            PerWavelength::Values(v) => {
                if v.len() != wavelengths_nm.len() {
                    return Err(Error::out_of_range(
                        &format!("{field} (length)"),
                        v.len(),
                        &format!("one value per wavelength: {}", wavelengths_nm.len()),
                    ));
                }
                v.clone()
            }
            PerWavelength::PowerLaw(p) => {
                check_positive(&format!("{field}.at_nm"), p.at_nm, 1e5)?;
                check_range(&format!("{field}.exponent"), p.exponent, -10.0, 10.0)?;
                wavelengths_nm
                    .iter()
                    .map(|l| p.value * (l / p.at_nm).powf(-p.exponent))
                    .collect()
            }
        };
        for (i, v) in values.iter().enumerate() {
            check_range(&format!("{field}[{i}]"), *v, 0.0, max)?;
        }
        Ok(values)
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct AtmosphereSpec {
    name: String,
    #[serde(default)]
    description: String,
    bottom_radius_m: f64,
    top_radius_m: f64,
    sun_angular_radius_deg: f64,
    wavelengths_nm: Vec<f64>,
    solar_irradiance: PerWavelength,
    #[serde(default)]
    ground_albedo: f64,
    /// Meteorological visibility at the ground, km: sets the aerosols' extinction by
    /// Koschmieder's law in place of `mie.scattering_per_m`.
    #[serde(default)]
    visibility_km: Option<f64>,
    rayleigh: SpeciesSpec,
    mie: SpeciesSpec,
    ozone: Option<OzoneSpec>,
    #[serde(default)]
    colour: Option<ColourSpec>,
}

/// A fitted map from the sampled spectrum to CIE XYZ, one weight a wavelength for each
/// of X, Y and Z (see [`Atmosphere::colour`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ColourSpec {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpeciesSpec {
    scale_height_m: f64,
    #[serde(default)]
    scattering_per_m: Option<PerWavelength>,
    #[serde(default = "one")]
    single_scattering_albedo: f64,
    phase: PhaseFunction,
}

fn one() -> f64 {
    1.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct OzoneSpec {
    #[serde(default = "yes")]
    enabled: bool,
    absorption_per_m: PerWavelength,
    center_altitude_m: f64,
    half_width_m: f64,
}

fn yes() -> bool {
    true
}

/// `s` as a TOML basic string: quotes, backslashes and control characters escaped the
/// way TOML reads them (Rust's `{:?}` writes `\u{c}`, which TOML refuses: a name with a
/// form feed made table files that could not be read back, found by fuzzing).
fn toml_string(s: &str) -> String {
    use std::fmt::Write;
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Koschmieder's constant: a black target vanishes against the horizon sky where its
/// contrast falls to 2 %, at `ln(50) = 3.912` extinction lengths.
const KOSCHMIEDER: f64 = 3.912;

/// The aerosols' scattering per wavelength, 1/m, that make the meteorological
/// visibility at the ground `visibility_km`: total extinction at 550 nm `3.912 / V`
/// (Koschmieder), less the air's (Rayleigh, interpolated log-log at 550 nm), taken as
/// the same at every wavelength (Angstrom exponent 0, as in the `earth` preset), times
/// the aerosols' single-scattering albedo.
fn aerosols_for_visibility(
    visibility_km: f64,
    rayleigh: &Species,
    wavelengths_nm: &[f64],
    albedo: f64,
) -> Result<Vec<f64>> {
    let k = wavelengths_nm
        .partition_point(|&w| w < 550.0)
        .clamp(1, wavelengths_nm.len() - 1);
    let (l0, l1) = (wavelengths_nm[k - 1].ln(), wavelengths_nm[k].ln());
    let (e0, e1) = (
        rayleigh.extinction_per_m[k - 1].max(1e-30).ln(),
        rayleigh.extinction_per_m[k].max(1e-30).ln(),
    );
    let air = (e0 + (550f64.ln() - l0) / (l1 - l0) * (e1 - e0)).exp();
    // The clearest air allowed still has some aerosol: 1 % of the air's extinction.
    let longest = KOSCHMIEDER / (1.01 * air) / 1000.0;
    check_range(
        "visibility_km",
        visibility_km,
        0.01,
        (longest * 10.0).floor() / 10.0,
    )?;
    let aerosol = KOSCHMIEDER / (visibility_km * 1000.0) - air;
    Ok(vec![aerosol * albedo; wavelengths_nm.len()])
}

/// A scattering constituent whose density falls off exponentially with altitude,
/// sky (A-2): `rho(h) = exp(-h / H)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Species {
    /// Scale height `H`, m.
    pub scale_height_m: f64,
    /// Scattering coefficient at density 1 (sea level), per wavelength, 1/m.
    pub scattering_per_m: Vec<f64>,
    /// Scattering / extinction, in (0, 1].
    pub single_scattering_albedo: f64,
    /// Extinction coefficient at density 1, per wavelength, 1/m: scattering divided by
    /// the single-scattering albedo.
    pub extinction_per_m: Vec<f64>,
    /// Angular distribution of the scattered light.
    pub phase: PhaseFunction,
}

impl Species {
    /// Relative density (1 at the ground) at `altitude_m`.
    #[inline]
    pub fn density(&self, altitude_m: f64) -> f64 {
        (-altitude_m / self.scale_height_m).exp()
    }
}

/// An absorbing layer whose density is a tent: 1 at `center_altitude_m`, falling
/// linearly to 0 at `half_width_m` above and below (the profile of Bruneton 2017).
#[derive(Debug, Clone, PartialEq)]
pub struct OzoneLayer {
    /// Whether the layer absorbs; a disabled layer is kept so `--ozone` can enable it.
    pub enabled: bool,
    /// Absorption coefficient at the tent's peak, per wavelength, 1/m.
    pub absorption_per_m: Vec<f64>,
    /// Altitude of the peak, m.
    pub center_altitude_m: f64,
    /// Distance from the peak to where the density reaches 0, m.
    pub half_width_m: f64,
}

impl OzoneLayer {
    /// Relative density (1 at the peak) at `altitude_m`.
    #[inline]
    pub fn density(&self, altitude_m: f64) -> f64 {
        (1.0 - (altitude_m - self.center_altitude_m).abs() / self.half_width_m).max(0.0)
    }
}

/// A validated atmosphere. Lengths in metres, angles in radians, coefficients in 1/m,
/// irradiance in the units the file gives (the presets: W m^-2 nm^-1), and every
/// radiance atmo computes is in those units per steradian.
#[derive(Debug, Clone, PartialEq)]
pub struct Atmosphere {
    /// Short name, e.g. `earth`.
    pub name: String,
    /// What the preset or file describes, for `--help` and docs.
    pub description: String,
    /// Radius of the ground sphere, m.
    pub bottom_radius_m: f64,
    /// Radius of the top of the atmosphere, m; nothing scatters above it.
    pub top_radius_m: f64,
    /// Angular radius of the sun's disc, rad.
    pub sun_angular_radius: f64,
    /// The wavelengths the spectrum is sampled at, nm, increasing.
    pub wavelengths_nm: Vec<f64>,
    /// Solar irradiance at the top of the atmosphere, per wavelength.
    pub solar_irradiance: Vec<f64>,
    /// Lambertian reflectance of the ground in [0, 1]; 0 is a black ground.
    pub ground_albedo: f64,
    /// Air molecules.
    pub rayleigh: Species,
    /// Aerosols.
    pub mie: Species,
    /// Ozone, absorbing only; `None` when absent. See [`Atmosphere::absorbing_ozone`].
    pub ozone: Option<OzoneLayer>,
    /// Where given (`[colour]`), the weights that take the radiance at
    /// [`Atmosphere::wavelengths_nm`] to CIE XYZ (X, Y, Z rows), fitted to the same
    /// atmosphere sampled at many wavelengths; else the spectrum is taken as piecewise
    /// linear between the samples ([`spectrum::SpectrumToRgb::for_atmosphere`]).
    pub colour: Option<[Vec<f64>; 3]>,
}

impl Atmosphere {
    /// The names of the embedded presets, the default first.
    pub fn preset_names() -> impl Iterator<Item = &'static str> {
        PRESETS.iter().map(|(n, _)| *n)
    }

    /// The embedded preset `name` (see [`Atmosphere::preset_names`]).
    pub fn preset(name: &str) -> Result<Self> {
        let (_, text) = PRESETS.iter().find(|(n, _)| *n == name).ok_or_else(|| {
            Error::out_of_range(
                "atmosphere preset",
                name,
                &Self::preset_names().collect::<Vec<_>>().join(", "),
            )
        })?;
        Self::from_toml_str(text, &format!("preset {name}"))
    }

    /// The measured-coefficient Earth of current sky models (Bruneton 2017, Hillaire
    /// 2020), with its ozone layer (off with [`Atmosphere::with_ozone`]): the default.
    pub fn earth() -> Self {
        Self::preset("earth").expect("embedded preset is valid")
    }

    /// Parses and validates a TOML description; `origin` names it in error messages.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        Self::from_spec(crate::error::from_toml(text, origin)?)
    }

    /// Reads, parses and validates a TOML file.
    pub fn from_toml_file(path: &std::path::Path) -> Result<Self> {
        let text = crate::files::read_toml(path, "atmosphere file")?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    fn from_spec(s: AtmosphereSpec) -> Result<Self> {
        check_range("bottom_radius_m", s.bottom_radius_m, 1e3, 1e9)?;
        if !(s.top_radius_m > s.bottom_radius_m && s.top_radius_m <= 2.0 * s.bottom_radius_m) {
            return Err(Error::out_of_range(
                "top_radius_m",
                s.top_radius_m,
                &format!("({}, {}]", s.bottom_radius_m, 2.0 * s.bottom_radius_m),
            ));
        }
        // Below 0.001 deg the disc's radiance (irradiance over its solid angle) leaves
        // f32's range in the pictures.
        check_range(
            "sun_angular_radius_deg",
            s.sun_angular_radius_deg,
            1e-3,
            10.0,
        )?;
        let l = &s.wavelengths_nm;
        if l.len() < 3 || l.len() > 64 {
            return Err(Error::out_of_range(
                "wavelengths_nm (length)",
                l.len(),
                "3 to 64 wavelengths",
            ));
        }
        for (i, w) in l.iter().enumerate() {
            check_range(&format!("wavelengths_nm[{i}]"), *w, 300.0, 1000.0)?;
            if i > 0 && *w <= l[i - 1] {
                return Err(Error::out_of_range(
                    &format!("wavelengths_nm[{i}]"),
                    w,
                    "strictly increasing wavelengths",
                ));
            }
        }
        check_range("ground_albedo", s.ground_albedo, 0.0, 1.0)?;
        let solar_irradiance = s.solar_irradiance.resolve("solar_irradiance", l, 1e6)?;
        let species = |name: &str, sp: &SpeciesSpec, given: Option<Vec<f64>>| -> Result<Species> {
            check_range(
                &format!("{name}.scale_height_m"),
                sp.scale_height_m,
                1.0,
                1e6,
            )?;
            check_range(
                &format!("{name}.single_scattering_albedo"),
                sp.single_scattering_albedo,
                1e-6,
                1.0,
            )?;
            sp.phase.validate(&format!("{name}.phase"))?;
            let field = format!("{name}.scattering_per_m");
            let scattering = match (&sp.scattering_per_m, given) {
                (Some(per), None) => per.resolve(&field, l, 1.0)?,
                (None, Some(values)) => values,
                (Some(_), Some(_)) => {
                    return Err(Error::Invalid(format!(
                        "{field} and visibility_km both set the aerosols: give one"
                    )))
                }
                (None, None) => {
                    return Err(Error::Invalid(format!(
                        "{field} is missing{}",
                        if name == "mie" {
                            " (or give visibility_km)"
                        } else {
                            ""
                        }
                    )))
                }
            };
            let extinction = scattering
                .iter()
                .map(|b| b / sp.single_scattering_albedo)
                .collect();
            Ok(Species {
                scale_height_m: sp.scale_height_m,
                scattering_per_m: scattering,
                single_scattering_albedo: sp.single_scattering_albedo,
                extinction_per_m: extinction,
                phase: sp.phase,
            })
        };
        let ozone = match s.ozone.as_ref() {
            None => None,
            Some(o) => {
                check_range("ozone.center_altitude_m", o.center_altitude_m, 0.0, 1e6)?;
                check_positive("ozone.half_width_m", o.half_width_m, 1e6)?;
                Some(OzoneLayer {
                    enabled: o.enabled,
                    absorption_per_m: o.absorption_per_m.resolve(
                        "ozone.absorption_per_m",
                        l,
                        1.0,
                    )?,
                    center_altitude_m: o.center_altitude_m,
                    half_width_m: o.half_width_m,
                })
            }
        };
        let rayleigh = species("rayleigh", &s.rayleigh, None)?;
        let from_visibility = match s.visibility_km {
            None => None,
            Some(v) => Some(aerosols_for_visibility(
                v,
                &rayleigh,
                l,
                s.mie.single_scattering_albedo,
            )?),
        };
        let colour = match s.colour {
            None => None,
            Some(c) => {
                for (name, row) in [("colour.x", &c.x), ("colour.y", &c.y), ("colour.z", &c.z)] {
                    if row.len() != s.wavelengths_nm.len() || row.iter().any(|w| !w.is_finite()) {
                        return Err(Error::Invalid(format!(
                            "{name} must hold one finite weight for each of the {} wavelengths",
                            s.wavelengths_nm.len()
                        )));
                    }
                }
                Some([c.x, c.y, c.z])
            }
        };
        Ok(Atmosphere {
            colour,
            rayleigh,
            mie: species("mie", &s.mie, from_visibility)?,
            name: s.name,
            description: s.description,
            bottom_radius_m: s.bottom_radius_m,
            top_radius_m: s.top_radius_m,
            sun_angular_radius: s.sun_angular_radius_deg.to_radians(),
            wavelengths_nm: s.wavelengths_nm,
            solar_irradiance,
            ground_albedo: s.ground_albedo,
            ozone,
        })
    }

    /// The atmosphere as TOML that [`Atmosphere::from_toml_str`] reads back to the same
    /// values (per-wavelength quantities written out as arrays), for table files.
    pub fn to_toml(&self) -> String {
        use std::fmt::Write;
        let list = |v: &[f64]| {
            let items: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
            format!("[{}]", items.join(", "))
        };
        let mut t = String::new();
        let _ = writeln!(t, "name = {}", toml_string(&self.name));
        let _ = writeln!(t, "description = {}", toml_string(&self.description));
        let _ = writeln!(t, "bottom_radius_m = {:?}", self.bottom_radius_m);
        let _ = writeln!(t, "top_radius_m = {:?}", self.top_radius_m);
        let _ = writeln!(
            t,
            "sun_angular_radius_deg = {:?}",
            self.sun_angular_radius.to_degrees()
        );
        let _ = writeln!(t, "wavelengths_nm = {}", list(&self.wavelengths_nm));
        let _ = writeln!(t, "solar_irradiance = {}", list(&self.solar_irradiance));
        let _ = writeln!(t, "ground_albedo = {:?}", self.ground_albedo);
        for (name, sp) in [("rayleigh", &self.rayleigh), ("mie", &self.mie)] {
            let _ = writeln!(t, "\n[{name}]");
            let _ = writeln!(t, "scale_height_m = {:?}", sp.scale_height_m);
            let _ = writeln!(t, "scattering_per_m = {}", list(&sp.scattering_per_m));
            let _ = writeln!(
                t,
                "single_scattering_albedo = {:?}",
                sp.single_scattering_albedo
            );
            let _ = writeln!(t, "phase = {}", sp.phase.to_toml());
        }
        if let Some(o) = &self.ozone {
            let _ = writeln!(t, "\n[ozone]\nenabled = {}", o.enabled);
            let _ = writeln!(t, "absorption_per_m = {}", list(&o.absorption_per_m));
            let _ = writeln!(t, "center_altitude_m = {:?}", o.center_altitude_m);
            let _ = writeln!(t, "half_width_m = {:?}", o.half_width_m);
        }
        if let Some([x, y, z]) = &self.colour {
            let _ = writeln!(t, "\n[colour]");
            let _ = writeln!(t, "x = {}\ny = {}\nz = {}", list(x), list(y), list(z));
        }
        t
    }

    /// Switches the ozone layer on or off (`--ozone`, `--no-ozone`); an error only when
    /// switching on a layer the atmosphere does not have.
    pub fn with_ozone(mut self, on: bool) -> Result<Self> {
        match self.ozone.as_mut() {
            Some(layer) => layer.enabled = on,
            None if on => {
                return Err(Error::Invalid(format!(
                    "atmosphere '{}' has no [ozone] table to switch on; add one to its TOML",
                    self.name
                )))
            }
            None => {}
        }
        Ok(self)
    }

    /// The ozone layer if it absorbs.
    pub fn absorbing_ozone(&self) -> Option<&OzoneLayer> {
        self.ozone.as_ref().filter(|o| o.enabled)
    }

    /// The sunlight reaching `altitude_m` from a sun at `elevation` rad: spectral
    /// irradiance on a surface facing the sun, W m^-2 nm^-1 per wavelength (the solar
    /// irradiance through the transmittance along the sun's ray, times the part of the
    /// disc above the horizon).
    pub fn direct_sunlight(&self, altitude_m: f64, elevation: f64) -> Vec<f64> {
        let mut t = vec![0.0f32; self.channels()];
        let r = self.bottom_radius_m + altitude_m;
        optical_depth::transmittance_to_sun(self, r, elevation.sin(), &mut t);
        self.solar_irradiance
            .iter()
            .zip(&t)
            .map(|(e, &t)| e * t as f64)
            .collect()
    }

    /// Number of wavelengths.
    pub fn channels(&self) -> usize {
        self.wavelengths_nm.len()
    }

    /// Altitude above the ground in metres of a point at radius `r`.
    #[inline]
    pub fn altitude(&self, r: f64) -> f64 {
        r - self.bottom_radius_m
    }

    /// Height of the atmosphere's top above the ground, m.
    pub fn thickness_m(&self) -> f64 {
        self.top_radius_m - self.bottom_radius_m
    }

    /// Relative densities (Rayleigh, Mie, ozone) at `altitude_m`; integrated along a
    /// path they give column densities, in metres of air at density 1.
    #[inline]
    pub fn densities(&self, altitude_m: f64) -> [f64; CONSTITUENTS] {
        [
            self.rayleigh.density(altitude_m),
            self.mie.density(altitude_m),
            self.absorbing_ozone()
                .map_or(0.0, |o| o.density(altitude_m)),
        ]
    }

    /// Extinction optical depth at wavelength index `c` of a path whose column
    /// densities are `columns`.
    #[inline]
    pub fn optical_depth(&self, columns: &[f64; CONSTITUENTS], c: usize) -> f64 {
        self.rayleigh.extinction_per_m[c] * columns[0]
            + self.mie.extinction_per_m[c] * columns[1]
            + self
                .absorbing_ozone()
                .map_or(0.0, |o| o.absorption_per_m[c] * columns[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names and descriptions with quotes, backslashes and control characters survive
    /// the trip through `to_toml` (table files embed it).
    #[test]
    fn strings_are_written_as_toml_reads_them() {
        let mut a = Atmosphere::earth();
        a.name = "a \"quoted\" name\\".into();
        a.description = "form\u{c}feed, tab\t, bell\u{7}, del\u{7f}, é, \u{85}".into();
        let back = Atmosphere::from_toml_str(&a.to_toml(), "written").unwrap();
        assert_eq!((back.name, back.description), (a.name, a.description));
    }

    /// `visibility_km = 20` sets the aerosols so that the total extinction at 550 nm
    /// at the ground is Koschmieder's 3.912 / 20 km; the ends of its range are named.
    #[test]
    fn visibility_sets_the_aerosols_by_koschmieder() {
        let earth = include_str!("../../presets/earth.toml");
        let with = |v: &str| {
            let text = earth.replace("scattering_per_m = 3.996e-6\n", "").replace(
                "ground_albedo = 0.1",
                &format!("ground_albedo = 0.1\nvisibility_km = {v}"),
            );
            Atmosphere::from_toml_str(&text, "visible")
        };
        let a = with("20").unwrap();
        // The air's extinction at 550 nm, log-log between 520 and 570 nm.
        let (e0, e1) = (
            a.rayleigh.extinction_per_m[2],
            a.rayleigh.extinction_per_m[3],
        );
        let f = (550f64 / 520.0).ln() / (570f64 / 520.0).ln();
        let air = (e0.ln() + f * (e1.ln() - e0.ln())).exp();
        let total = air + a.mie.extinction_per_m[3];
        assert!((total - 3.912 / 20_000.0).abs() < 1e-12, "{total}");
        assert!(a
            .mie
            .extinction_per_m
            .iter()
            .all(|&e| e == a.mie.extinction_per_m[0]));
        // Hazier means more aerosol; past what pure air allows is refused by name.
        assert!(with("5").unwrap().mie.extinction_per_m[0] > a.mie.extinction_per_m[0]);
        for bad in ["400", "0", "nan"] {
            let e = with(bad).unwrap_err().to_string();
            assert!(e.starts_with("visibility_km = "), "{bad}: {e}");
        }
        // Both ways of giving the aerosols at once is refused; so is neither.
        let both = earth.replace(
            "ground_albedo = 0.1",
            "ground_albedo = 0.1\nvisibility_km = 20",
        );
        let e = Atmosphere::from_toml_str(&both, "both")
            .unwrap_err()
            .to_string();
        assert!(e.contains("give one"), "{e}");
        let neither = earth.replace("scattering_per_m = 3.996e-6\n", "");
        let e = Atmosphere::from_toml_str(&neither, "neither")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("mie.scattering_per_m is missing (or give visibility_km)"),
            "{e}"
        );
    }

    #[test]
    fn to_toml_reads_back_to_the_same_atmosphere() {
        for name in Atmosphere::preset_names() {
            let a = Atmosphere::preset(name).unwrap();
            let a = a.clone().with_ozone(true).unwrap_or(a);
            let mut b = Atmosphere::from_toml_str(&a.to_toml(), "round trip").unwrap();
            // Degrees to radians and back may move the last bit.
            assert!((b.sun_angular_radius - a.sun_angular_radius).abs() < 1e-15);
            b.sun_angular_radius = a.sun_angular_radius;
            assert_eq!(a, b, "{name}");
        }
    }

    #[test]
    fn presets_load_and_differ() {
        let earth = Atmosphere::earth();
        let paper = Atmosphere::preset("paper").unwrap();
        assert_eq!(earth.bottom_radius_m, 6_360_000.0);
        assert_eq!(earth.top_radius_m, 6_420_000.0);
        assert_ne!(earth.mie.phase, paper.mie.phase);
        // Ozone absorbs by default, and can be switched off for the paper's model.
        assert!(earth
            .clone()
            .with_ozone(false)
            .unwrap()
            .absorbing_ozone()
            .is_none());
        // Ozone absorbs most in the orange (Chappuis band), not in the blue.
        let o = earth.absorbing_ozone().expect("ozone is on by default");
        let peak = o.absorption_per_m.iter().cloned().fold(0.0, f64::max);
        assert!(o.absorption_per_m[0] < 0.5 * peak && peak > 1e-6);
        assert!(Atmosphere::preset("paper")
            .unwrap()
            .with_ozone(true)
            .is_err());
        // Rayleigh scattering follows lambda^-4 closely in both presets.
        for a in [&earth, &paper] {
            let (l0, l1) = (a.wavelengths_nm[0], *a.wavelengths_nm.last().unwrap());
            let (b0, b1) = (
                a.rayleigh.scattering_per_m[0],
                *a.rayleigh.scattering_per_m.last().unwrap(),
            );
            let ratio = (b0 / b1) / (l1 / l0).powi(4);
            assert!((ratio - 1.0).abs() < 0.01, "{}: {ratio}", a.name);
        }
    }

    #[test]
    fn mie_extinction_is_scattering_over_albedo() {
        let earth = Atmosphere::earth();
        for c in 0..earth.channels() {
            let ratio = earth.mie.scattering_per_m[c] / earth.mie.extinction_per_m[c];
            assert!((ratio - 0.9).abs() < 1e-12);
        }
    }

    fn earth_text() -> String {
        PRESETS[0].1.to_string()
    }

    #[test]
    fn unknown_keys_are_refused_with_their_line() {
        let text = earth_text().replacen("ground_albedo", "ground_albdo", 1);
        let err = Atmosphere::from_toml_str(&text, "t.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("ground_albdo") && err.contains("line"),
            "{err}"
        );
    }

    #[test]
    fn negative_and_nan_coefficients_are_refused() {
        let text = earth_text().replacen("scale_height_m = 1200.0", "scale_height_m = -5.0", 1);
        let err = Atmosphere::from_toml_str(&text, "t")
            .unwrap_err()
            .to_string();
        assert!(err.contains("mie.scale_height_m"), "{err}");
        let text = earth_text().replacen(
            "single_scattering_albedo = 0.9",
            "single_scattering_albedo = nan",
            1,
        );
        let err = Atmosphere::from_toml_str(&text, "t")
            .unwrap_err()
            .to_string();
        assert!(err.contains("mie.single_scattering_albedo"), "{err}");
    }

    #[test]
    fn arrays_must_match_the_wavelengths() {
        let text = earth_text().replacen("solar_irradiance = [", "solar_irradiance = [1.0, ", 1);
        let err = Atmosphere::from_toml_str(&text, "t")
            .unwrap_err()
            .to_string();
        assert!(err.contains("solar_irradiance (length)"), "{err}");
    }

    #[test]
    fn power_law_resolves_per_wavelength() {
        // The paper preset gives Rayleigh as 1.28e-5 /m at 550 nm times (550/lambda)^4.
        let paper = Atmosphere::preset("paper").unwrap();
        for (l, b) in paper
            .wavelengths_nm
            .iter()
            .zip(&paper.rayleigh.scattering_per_m)
        {
            let expect = 1.28e-5 * (550.0 / l).powi(4);
            assert!(
                (b - expect).abs() < 1e-12 * expect.max(1.0),
                "{l}: {b} vs {expect}"
            );
        }
    }
}
