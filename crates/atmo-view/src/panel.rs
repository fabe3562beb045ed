//! What the modes' panels share: sliders that do not edit by being shown, the tone
//! maps by name, and the edits a panel's widgets made.

use atmo::image::ToneMap;

use crate::input::Input;

/// A slider for `value` over `range` that never changes a value by showing it: a
/// value outside the range (a sun azimuth of -150 deg, a 2 Mcd light) stays as it is
/// until the user moves the slider (egui clamps it by default, which would be an edit
/// nobody made).
pub fn slider<N: egui::emath::Numeric>(
    value: &mut N,
    range: std::ops::RangeInclusive<N>,
) -> egui::Slider<'_> {
    egui::Slider::new(value, range).clamping(egui::SliderClamping::Edits)
}

/// The tone maps by the names `--tone-map` and a scene's `display.tone_map` take.
pub const TONES: [(&str, ToneMap); 3] = [
    ("clamp", ToneMap::Clamp),
    ("exponential", ToneMap::Exponential),
    ("aces", ToneMap::Aces),
];

/// A tone map's name.
pub fn tone_name(tone: ToneMap) -> &'static str {
    TONES
        .iter()
        .find(|(_, t)| *t == tone)
        .map_or("", |(n, _)| n)
}

/// The tone map named `name`, or an error saying which names there are.
pub fn tone_named(field: &str, name: &str) -> atmo::Result<ToneMap> {
    TONES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
        .ok_or_else(|| not(field, name, "clamp, exponential or aces"))
}

/// The display's widgets: the exposure's slider and the tone map's combo box.
pub fn display(ui: &mut egui::Ui, exposure: &mut f32, tone: &mut ToneMap) {
    ui.add(
        slider(exposure, 0.001..=100.0)
            .logarithmic(true)
            .text("exposure"),
    );
    tone_combo(ui, tone);
}

/// A combo box choosing the tone map `tone`.
pub fn tone_combo(ui: &mut egui::Ui, tone: &mut ToneMap) {
    egui::ComboBox::from_label("tone map")
        .selected_text(tone_name(*tone))
        .show_ui(ui, |ui| {
            for (name, t) in TONES {
                ui.selectable_value(tone, t, name);
            }
        });
}

/// The panel edits that take parameters from `old` to `new` (each a list of a
/// parameter's name and value, in the same order).
pub fn edits(new: Vec<(&'static str, String)>, old: Vec<(&'static str, String)>) -> Vec<Input> {
    new.into_iter()
        .zip(old)
        .filter(|(new, old)| new != old)
        .map(|((name, value), _)| Input::Set(name.to_string(), value))
        .collect()
}

/// The finite number `value` for the parameter `name`, or an error naming both.
pub fn number(name: &str, value: &str) -> atmo::Result<f64> {
    value
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| not(name, value, "a finite number"))
}

/// The error for `value` given to the parameter `name`, which takes `allowed`.
pub fn not(name: &str, value: &str, allowed: &str) -> atmo::Error {
    atmo::Error::Invalid(format!("{name}: '{value}' is not {allowed}"))
}
