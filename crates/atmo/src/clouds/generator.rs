//! A deterministic generator of cumulus-like particle clouds: a cauliflower of rounded
//! cells on a flat base, filled with particles whose sizes shrink toward the surface so
//! the edges carry fine detail, as in the paper's Figs. 5-7 (9,382 to 60,134 particles).

use glam::Vec3;

use super::particles::Particle;

/// SplitMix64 (Steele, Lea and Flood 2014): a 64-bit generator whose sequence is fixed
/// by its definition, so a seed gives the same cloud on every machine and every version
/// of every crate. (`rand`'s `StdRng` does not promise that across versions.)
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// The generator started at `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A uniform number in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A uniform number in [0, 1) with 53 bits.
    pub fn unit_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniform number in [a, b).
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.unit()
    }
}

/// What the cumulus generator makes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cumulus {
    /// Particles.
    pub particles: usize,
    /// Seed of the random sequence.
    pub seed: u64,
    /// Width of the cloud, m.
    pub width: f32,
    /// Height of its flat base above the ground, m.
    pub base: f32,
    /// Peak extinction of each particle, 1/m.
    pub density: f32,
    /// Single-scattering albedo of the droplets.
    pub albedo: f32,
}

impl Default for Cumulus {
    /// A 1.2 km cumulus at 1.5 km with 60,134 particles (the paper's largest).
    fn default() -> Self {
        Cumulus {
            particles: 60_134,
            seed: 1,
            width: 1200.0,
            base: 1500.0,
            density: 0.04,
            albedo: 0.99,
        }
    }
}

/// One rounded cell of the cauliflower.
#[derive(Debug, Clone, Copy)]
struct Cell {
    centre: Vec3,
    radius: f32,
}

impl Cumulus {
    /// The cloud's particles.
    pub fn generate(&self) -> Vec<Particle> {
        let mut rng = SplitMix64::new(self.seed);
        let w = self.width;
        // The cells: a broad central tower, a ring of shoulders and a few turrets on top,
        // their sizes and places jittered by the seed.
        let mut cells = vec![Cell {
            centre: Vec3::new(0.0, 0.28 * w, 0.0),
            radius: 0.32 * w,
        }];
        let shoulders = 6 + (rng.next_u64() % 3) as usize;
        for k in 0..shoulders {
            let angle =
                (k as f32 + rng.range(-0.3, 0.3)) * std::f32::consts::TAU / shoulders as f32;
            let d = rng.range(0.28, 0.4) * w;
            let radius = rng.range(0.16, 0.24) * w;
            cells.push(Cell {
                centre: Vec3::new(
                    d * angle.cos(),
                    radius * rng.range(0.7, 1.0),
                    d * angle.sin(),
                ),
                radius,
            });
        }
        for _ in 0..4 {
            let angle = rng.range(0.0, std::f32::consts::TAU);
            let d = rng.range(0.0, 0.18) * w;
            cells.push(Cell {
                centre: Vec3::new(d * angle.cos(), rng.range(0.5, 0.62) * w, d * angle.sin()),
                radius: rng.range(0.12, 0.18) * w,
            });
        }
        // Bulges on the upper surfaces of the big cells: the cauliflower's smaller scale.
        let big = cells.clone();
        for _ in 0..48 {
            let cell = big[(rng.next_u64() % big.len() as u64) as usize];
            // A direction on the cell's upper side.
            let (a, up) = (rng.range(0.0, std::f32::consts::TAU), rng.range(0.05, 1.0));
            let side = (1.0 - up * up).sqrt();
            let dir = Vec3::new(side * a.cos(), up, side * a.sin());
            let radius = rng.range(0.05, 0.1) * w;
            cells.push(Cell {
                centre: cell.centre + dir * (cell.radius - 0.4 * radius),
                radius,
            });
        }
        // How deep inside the union of cells a point is, as a fraction of its cell.
        let depth = |p: Vec3| {
            cells
                .iter()
                .map(|c| 1.0 - (p - c.centre).length() / c.radius)
                .fold(f32::NEG_INFINITY, f32::max)
        };
        let lo = Vec3::new(-0.75 * w, 0.0, -0.75 * w);
        let hi = Vec3::new(0.75 * w, 0.85 * w, 0.75 * w);
        // Particle radius: large deep inside (few particles fill the core), small at the
        // surface (the cauliflower's detail); scaled so the count fills the volume.
        let base_radius = 0.6 * w / (self.particles as f32).cbrt();
        let mut particles = Vec::with_capacity(self.particles);
        while particles.len() < self.particles {
            let p = Vec3::new(
                rng.range(lo.x, hi.x),
                rng.range(lo.y, hi.y),
                rng.range(lo.z, hi.z),
            );
            let d = depth(p);
            // Keep points inside, denser toward the surface (where detail is).
            if d <= 0.0 || rng.unit() > 0.35 + 0.65 * (1.0 - d).powi(2) {
                continue;
            }
            let radius = base_radius * (0.9 + 1.6 * d) * rng.range(0.8, 1.2);
            // The flat base: no particle reaches below it.
            if p.y < radius {
                continue;
            }
            particles.push(Particle {
                position: p + Vec3::new(0.0, self.base, 0.0),
                radius,
                density: self.density,
                albedo: self.albedo,
            });
        }
        particles
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_gives_the_same_cloud_and_another_seed_another() {
        let c = Cumulus {
            particles: 2000,
            ..Cumulus::default()
        };
        let (a, b) = (c.generate(), c.generate());
        assert_eq!(a, b);
        assert_eq!(a.len(), 2000);
        let other = Cumulus { seed: 2, ..c }.generate();
        assert_ne!(a, other);
        // The first draws of the generator are fixed by its definition.
        let mut rng = SplitMix64::new(1234567);
        assert_eq!(rng.next_u64(), 6_457_827_717_110_365_317);
    }

    #[test]
    fn the_cloud_sits_on_its_base_within_its_width() {
        let c = Cumulus {
            particles: 5000,
            ..Cumulus::default()
        };
        for p in c.generate() {
            assert!(p.position.y - p.radius >= c.base - 1e-3, "{p:?}");
            assert!(p.position.x.abs() <= 0.75 * c.width && p.position.z.abs() <= 0.75 * c.width);
            assert!(p.radius > 0.0 && p.density == c.density);
        }
    }
}
