// Functions every pass may use, each the WGSL twin of one Rust function (named beside
// it) and held to it by tests/twins.rs over a grid of inputs. The constants they use
// (PHASE_*) come from the prelude atmo_gpu::wgsl generates from the Rust.

const PI: f32 = 3.14159265;
const HALF_PI: f32 = 1.5707963;

// acos within 7e-5 rad (Abramowitz and Stegun 4.4.45): atmo::fast::fast_acos. NaN in,
// NaN out, as the CPU's.
fn fast_acos(x: f32) -> f32 {
    let a = min(abs(x), 1.0);
    let r = sqrt(1.0 - a) * (1.5707288 + a * (-0.2121144 + a * (0.074261 - 0.0187293 * a)));
    return select(r, 3.14159265 - r, x < 0.0);
}

// atan for x >= 0 within 2e-5 rad: atmo::fast::fast_atan.
fn fast_atan(x: f32) -> f32 {
    let flip = x > 1.0;
    let y = select(x, 1.0 / x, flip);
    let y2 = y * y;
    let p = y * (0.999866 + y2 * (-0.3302995 + y2 * (0.180141 + y2 * (-0.085133 + y2 * 0.0208351))));
    return select(p, HALF_PI - p, flip);
}

// atan2(y, x) in [-pi, pi] within 2e-5 rad, 0 at the origin: atmo::fast::fast_atan2.
fn fast_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    if ax == 0.0 && ay == 0.0 {
        return 0.0;
    }
    var a = select(HALF_PI - fast_atan(ax / ay), fast_atan(ay / ax), ax >= ay);
    a = select(a, PI - a, x < 0.0);
    return select(a, -a, y < 0.0);
}

// Interleaved gradient noise in [0, 1): atmo::fast::interleaved_offset.
fn interleaved_offset(x: u32, y: u32) -> f32 {
    let f = fract(0.06711056 * f32(x) + 0.00583715 * f32(y));
    return fract(52.982918 * f);
}

// erf within 1.2e-7 (Numerical Recipes' erfcc): atmo::clouds::particles::erf.
fn erf(x: f32) -> f32 {
    let z = abs(x);
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418
        + t * (-0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587
        + t * (-0.82215223 + t * 0.17087277))))))));
    let erfc = t * exp(poly);
    return select(erfc - 1.0, 1.0 - erfc, x >= 0.0);
}

fn henyey_greenstein(g: f32, c: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * c;
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom));
}

// The phase function of kind `kind` (a PHASE_* code) with parameter `p` (g or the
// exponent) at scattering-angle cosine `c`, 1/sr: atmo::atmosphere::PhaseFunction.
fn phase_function(kind: u32, p: f32, c: f32) -> f32 {
    switch kind {
        case PHASE_RAYLEIGH: {
            return 3.0 / (16.0 * PI) * (1.0 + c * c);
        }
        case PHASE_PAPER_MIE: {
            let half = 0.5 * (1.0 + c);
            return (1.0 + 50.0 * half * half * half) / (54.0 * PI);
        }
        case PHASE_HENYEY_GREENSTEIN: {
            return henyey_greenstein(p, c);
        }
        case PHASE_CORNETTE_SHANKS: {
            let denom = 1.0 + p * p - 2.0 * p * c;
            return 3.0 / (8.0 * PI) * (1.0 - p * p) * (1.0 + c * c) / ((2.0 + p * p) * denom * sqrt(denom));
        }
        case PHASE_PAPER_HAZE: {
            let half = max(0.5 * (1.0 + c), 0.0);
            let norm = 4.0 * PI * (1.0 + 18.0 / (p + 2.0));
            return (1.0 + 9.0 * pow(half, 0.5 * p)) / norm;
        }
        case PHASE_CLOUD_MIE: {
            return 0.75 * henyey_greenstein(0.8, c) + 0.25 * henyey_greenstein(-0.3, c);
        }
        default: {
            return 0.0;
        }
    }
}

// The tone-mapped value of the exposed linear value x (TONE_* codes):
// atmo::image::ToneMap::apply.
fn tone_map(kind: u32, x: f32) -> f32 {
    let y = max(x, 0.0);
    switch kind {
        case TONE_CLAMP: {
            return min(y, 1.0);
        }
        case TONE_ACES: {
            return clamp((y * (2.51 * y + 0.03)) / (y * (2.43 * y + 0.59) + 0.14), 0.0, 1.0);
        }
        default: {
            return 1.0 - exp(-y);
        }
    }
}

// The sRGB transfer function of a linear value in [0, 1]: atmo::image::srgb_encode.
fn srgb_encode(v: f32) -> f32 {
    if v <= 0.0031308 {
        return 12.92 * v;
    }
    return 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}
