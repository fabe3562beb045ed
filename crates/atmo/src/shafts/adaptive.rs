//! Adaptive sampling of the scattered light across the picture: not in the paper, which
//! draws every plane over every pixel. In haze the light scattered toward the eye
//! changes slowly from pixel to pixel except at a beam's edge, a shadow's edge, a
//! gobo's pattern or the lamp; there it is computed pixel by pixel, elsewhere it is
//! interpolated.
//!
//! The picture is covered by cells whose corners are computed, first [`COARSEST`]
//! pixels apart. Each cell's centre is computed too: where the corners' contrast is low
//! and their bilinear interpolation gives the centre within the tolerance
//! ([`Tolerance`]), the cell's other pixels are interpolated, each only if the caller's
//! guard allows it (for the shafts: the pixel's ray ends where interpolating the
//! corners' ends puts it, so an object's silhouette or a thin post between the samples
//! is caught, and the pixel is not near a lamp's image); where they do not, the
//! midpoints of the cell's sides are computed and the cell is split in four, down to
//! single pixels. Every computed value is exact; the error is that of bilinear
//! interpolation where the centre showed it small, and what the samples and the guard
//! cannot see: a detail narrower than the cells of the level it falls in that misses
//! their samples (a far beam seen end-on, the shadow sheet of a thin rod, a gobo's
//! fine lines).
//!
//! The error this adds to the shafts' pictures is measured against the exact picture by
//! `atmo bench shafts` (`shafts.fig6` and `shafts.stage`, against `-every-pixel`).

use glam::Vec3;
use rayon::prelude::*;

/// The spacing of the first cells' corners, pixels.
pub const COARSEST: u32 = 4;

/// When the interpolation of a cell's corners stands for its pixels: the corners'
/// contrast, `(max - min) / (max + min)` per channel, at most `contrast` (the test of
/// Mitchell's adaptive sampling, 1987: a step or a peak between samples shows in it
/// even where the centre happens to fit), and at the centre every channel within
/// `relative` of the computed value (the curvature a smooth gradient's corners do not
/// show). Both are taken of the values plus `floor`, so that near black, where the
/// light is faint, a relative change of a trace does not split cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// Largest contrast of the corners.
    pub contrast: f32,
    /// Allowed difference at the centre, relative.
    pub relative: f32,
    /// Added to the values before the ratios are taken, in the pixels' units.
    pub floor: f32,
}

impl Tolerance {
    /// Whether the bilinear interpolation of `corners`, `estimate` at the centre, stands
    /// for a cell whose centre is `exact`.
    fn stands(&self, corners: [Vec3; 4], estimate: Vec3, exact: Vec3) -> bool {
        let floor = Vec3::splat(self.floor);
        let (lo, hi) = (
            corners[0].min(corners[1]).min(corners[2].min(corners[3])),
            corners[0].max(corners[1]).max(corners[2].max(corners[3])),
        );
        (hi - lo).cmple(self.contrast * (hi + lo + floor)).all()
            && (estimate - exact)
                .abs()
                .cmple(self.relative * (exact.abs() + floor))
                .all()
    }
}

/// What became of the picture's pixels.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Pixels computed.
    pub computed: usize,
    /// Pixels interpolated.
    pub interpolated: usize,
}

impl Counts {
    /// The share of the pixels computed, in [0, 1].
    pub fn computed_share(&self) -> f64 {
        self.computed as f64 / (self.computed + self.interpolated) as f64
    }
}

/// A cell of the refinement: pixel columns `x0..=x1`, rows `y0..=y1`, corners computed.
#[derive(Debug, Clone, Copy)]
struct Cell {
    x0: u32,
    x1: u32,
    y0: u32,
    y1: u32,
}

impl Cell {
    /// The pixel at the middle (rounded toward the first corner).
    fn centre(&self) -> (u32, u32) {
        ((self.x0 + self.x1) / 2, (self.y0 + self.y1) / 2)
    }

    /// The corners' pixel indices in a picture `width` wide: (x0, y0), (x1, y0),
    /// (x0, y1), (x1, y1).
    fn corners(&self, width: u32) -> [u32; 4] {
        [
            self.y0 * width + self.x0,
            self.y0 * width + self.x1,
            self.y1 * width + self.x0,
            self.y1 * width + self.x1,
        ]
    }

    /// The bilinear weights of the corners at pixel (x, y) of the cell.
    fn weights(&self, x: u32, y: u32) -> [f32; 4] {
        let along = |a: u32, a0: u32, a1: u32| {
            if a1 > a0 {
                (a - a0) as f32 / (a1 - a0) as f32
            } else {
                0.0
            }
        };
        let (fx, fy) = (along(x, self.x0, self.x1), along(y, self.y0, self.y1));
        [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ]
    }
}

/// The corners' values weighted.
fn bilinear(c: [Vec3; 4], w: [f32; 4]) -> Vec3 {
    c[0] * w[0] + c[1] * w[1] + c[2] * w[2] + c[3] * w[3]
}

/// No cell: the pixel is computed.
const NONE: u32 = u32::MAX;

/// The memory of [`refine`] the size of its picture, kept by each thread between calls:
/// fresh memory costs a page fault a page at first touch, which on Fig. 6 (720 x 480)
/// in the bench's process cost some 8 ms of a 34 ms adaptive frame. Taken out while in
/// use, so a call nested on the same thread (a rayon worker that steals another
/// picture's work while it waits) finds none and makes its own.
#[derive(Default)]
struct Scratch {
    /// The computed pixels' values.
    values: Vec<Vec3>,
    /// Whether each pixel was computed.
    computed: Vec<bool>,
    /// Each pixel's finest cell that stood, as an index into the kept cells.
    owner: Vec<u32>,
}

thread_local! {
    static SCRATCH: std::cell::Cell<Scratch> = std::cell::Cell::new(Scratch::default());
}

/// `v` cleared and filled with `n` copies of `value`, in the memory it has.
fn refill<T: Copy>(v: &mut Vec<T>, n: usize, value: T) -> &mut [T] {
    v.clear();
    v.resize(n, value);
    v
}

/// Adds the values of a `width x height` picture to `out` (row by row, that size):
/// computed by `compute(pixels, values)` (pixel indices `y * width + x` in, their
/// values out; each list in one call, which may spread it over threads) where needed,
/// interpolated elsewhere. `interpolable(pixel, corners, weights)` says whether a pixel
/// may take the bilinear interpolation of the corner pixels with those weights.
///
/// The cells are decided level by level, computing the centres and then the split
/// points; every pixel not computed then takes the interpolation of the finest cell
/// that holds it and stood the test, over both cores, and those the guard refuses are
/// computed last. Added into the caller's buffer rather than returned in a new one, its
/// own per-pixel memory kept by the thread between calls: fresh memory costs a page
/// fault a page (`Scratch`).
pub fn refine(
    (width, height): (u32, u32),
    tolerance: Tolerance,
    mut compute: impl FnMut(&[u32], &mut [Vec3]),
    interpolable: impl Fn(u32, [u32; 4], [f32; 4]) -> bool + Sync,
    out: &mut [Vec3],
) -> Counts {
    let n = (width * height) as usize;
    assert_eq!(out.len(), n, "a {width} x {height} picture");
    let mut scratch = SCRATCH.take();
    let Scratch {
        values,
        computed,
        owner,
    } = &mut scratch;
    let (values, computed) = (refill(values, n, Vec3::ZERO), refill(computed, n, false));
    let index = |x: u32, y: u32| y * width + x;
    // Columns and rows of the first corners: every COARSEST-th, and the last.
    let grid = |size: u32| -> Vec<u32> {
        let mut at: Vec<u32> = (0..size).step_by(COARSEST as usize).collect();
        if at.last() != Some(&(size - 1)) {
            at.push(size - 1);
        }
        at
    };
    let (xs, ys) = (grid(width), grid(height));
    // Consecutive corners; a picture one pixel wide or high has cells of no width.
    let pairs = |at: &[u32]| -> Vec<(u32, u32)> {
        match at {
            [only] => vec![(*only, *only)],
            _ => at.windows(2).map(|w| (w[0], w[1])).collect(),
        }
    };
    let (x_pairs, y_pairs) = (pairs(&xs), pairs(&ys));
    let mut cells: Vec<Cell> = y_pairs
        .iter()
        .flat_map(|&(y0, y1)| x_pairs.iter().map(move |&(x0, x1)| Cell { x0, x1, y0, y1 }))
        .collect();
    let mut queue: Vec<u32> = ys
        .iter()
        .flat_map(|&y| xs.iter().map(move |&x| index(x, y)))
        .collect();
    let mut batch = Vec::new();
    // Computes the queued pixels (each once) and empties the queue.
    let mut run = |queue: &mut Vec<u32>, values: &mut [Vec3], computed: &mut [bool]| {
        queue.retain(|&p| !std::mem::replace(&mut computed[p as usize], true));
        compute(queue, refill(&mut batch, queue.len(), Vec3::ZERO));
        for (&p, v) in queue.iter().zip(&batch) {
            values[p as usize] = *v;
        }
        queue.clear();
    };
    run(&mut queue, values, computed);
    // The cells that stood the test, coarsest first.
    let mut kept: Vec<Cell> = Vec::new();
    while !cells.is_empty() {
        queue.extend(cells.iter().map(|c| {
            let (x, y) = c.centre();
            index(x, y)
        }));
        run(&mut queue, values, computed);
        let mut split = Vec::new();
        for cell in cells {
            let c = cell.corners(width).map(|p| values[p as usize]);
            let (cx, cy) = cell.centre();
            let estimate = bilinear(c, cell.weights(cx, cy));
            if tolerance.stands(c, estimate, values[index(cx, cy) as usize]) {
                kept.push(cell);
                continue;
            }
            // Split at the midpoints of the sides longer than one pixel.
            let xm = (cell.x1 - cell.x0 >= 2).then_some(cx);
            let ym = (cell.y1 - cell.y0 >= 2).then_some(cy);
            let cols: Vec<u32> = [Some(cell.x0), xm, Some(cell.x1)]
                .into_iter()
                .flatten()
                .collect();
            let rows: Vec<u32> = [Some(cell.y0), ym, Some(cell.y1)]
                .into_iter()
                .flatten()
                .collect();
            queue.extend(
                rows.iter()
                    .flat_map(|&y| cols.iter().map(move |&x| index(x, y))),
            );
            for y in rows.windows(2) {
                for x in cols.windows(2) {
                    if x[1] - x[0] >= 2 || y[1] - y[0] >= 2 {
                        split.push(Cell {
                            x0: x[0],
                            x1: x[1],
                            y0: y[0],
                            y1: y[1],
                        });
                    }
                }
            }
        }
        run(&mut queue, values, computed);
        cells = split;
    }
    // Each pixel's finest cell that stood (later, finer cells paint over).
    let owner = refill(owner, n, NONE);
    for (k, cell) in kept.iter().enumerate() {
        for y in cell.y0..=cell.y1 {
            owner[index(cell.x0, y) as usize..=index(cell.x1, y) as usize].fill(k as u32);
        }
    }
    // Computed values added, the others interpolated where the guard allows, over both
    // cores; the pixels it refuses listed, computed and added last.
    queue.par_extend(out.par_iter_mut().enumerate().filter_map(|(p, o)| {
        if computed[p] {
            *o += values[p];
            return None;
        }
        let cell = kept[owner[p] as usize];
        let p = p as u32;
        let corners = cell.corners(width);
        let weights = cell.weights(p % width, p / width);
        if !interpolable(p, corners, weights) {
            return Some(p);
        }
        *o += bilinear(corners.map(|c| values[c as usize]), weights);
        None
    }));
    let refused = queue.clone();
    run(&mut queue, values, computed);
    for p in refused {
        out[p as usize] += values[p as usize];
    }
    let done = computed.iter().filter(|&&c| c).count();
    SCRATCH.set(scratch);
    Counts {
        computed: done,
        interpolated: n - done,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOLERANCE: Tolerance = Tolerance {
        contrast: 0.25,
        relative: 0.01,
        floor: 0.01,
    };

    /// `f` refined over a `w x h` picture: the values, the counts, and how many pixels
    /// `compute` was asked for in all (each exactly once).
    fn refined(
        (w, h): (u32, u32),
        f: impl Fn(u32, u32) -> Vec3,
        guard: impl Fn(u32, [u32; 4], [f32; 4]) -> bool + Sync,
    ) -> (Vec<Vec3>, Counts) {
        let mut asked = vec![0u32; (w * h) as usize];
        let mut values = vec![Vec3::ZERO; (w * h) as usize];
        let counts = refine(
            (w, h),
            TOLERANCE,
            |pixels, out| {
                for (p, o) in pixels.iter().zip(out) {
                    asked[*p as usize] += 1;
                    *o = f(p % w, p / w);
                }
            },
            guard,
            &mut values,
        );
        assert!(asked.iter().all(|&n| n <= 1), "a pixel computed twice");
        assert_eq!(asked.iter().filter(|&&n| n == 1).count(), counts.computed);
        (values, counts)
    }

    #[test]
    fn a_smooth_picture_is_mostly_interpolated_and_within_the_tolerance() {
        let (w, h) = (203, 101);
        let f = |x: u32, y: u32| {
            let (x, y) = (x as f32 / w as f32, y as f32 / h as f32);
            Vec3::new(1.0 + 0.5 * x, 2.0 - y * y, 0.5 + 0.2 * (3.0 * x).sin())
        };
        let (values, counts) = refined((w, h), f, |_, _, _| true);
        assert_eq!(counts.computed + counts.interpolated, (w * h) as usize);
        // About two pixels in COARSEST^2 computed (a corner and a centre), every other
        // one interpolated.
        assert!(counts.computed < (w * h) as usize / 7, "{counts:?}");
        for (p, v) in values.iter().enumerate() {
            let exact = f(p as u32 % w, p as u32 / w);
            assert!(
                ((*v - exact).abs() / exact).max_element() < 0.01,
                "{p}: {v} against {exact}"
            );
        }
    }

    #[test]
    fn an_edge_is_computed_pixel_by_pixel_and_the_rest_interpolated() {
        let (w, h) = (64, 48);
        // A step along a slanted line, and a lamp-like peak.
        let f = |x: u32, y: u32| {
            let step = if 2 * x + y > 70 { 1.0 } else { 0.2 };
            let r2 = (x as f32 - 40.0).powi(2) + (y as f32 - 10.0).powi(2);
            Vec3::splat(step + 50.0 / (1.0 + r2))
        };
        let (values, counts) = refined((w, h), f, |_, _, _| true);
        let mut worst = 0.0f32;
        for (p, v) in values.iter().enumerate() {
            let exact = f(p as u32 % w, p as u32 / w);
            worst = worst.max(((*v - exact).abs() / exact).max_element());
        }
        assert!(worst < 0.02, "worst relative error {worst}");
        // Most of the picture is far from the edge and the peak.
        assert!(counts.interpolated > counts.computed, "{counts:?}");
    }

    #[test]
    fn the_guard_catches_what_passes_between_corners() {
        let (w, h) = (64, 48);
        // A line one pixel wide, on no corner's or centre's column: all agree on zero.
        let f = |x: u32, _y: u32| Vec3::splat(if x == 5 { 1.0 } else { 0.0 });
        let (blind, _) = refined((w, h), f, |_, _, _| true);
        assert!(
            blind.iter().all(|v| *v == Vec3::ZERO),
            "the corners cannot see it"
        );
        // A guard that knows where the line is (the shafts' lit stretches) refuses it.
        let (values, counts) = refined((w, h), f, |p, _, _| p % w != 5);
        for (p, v) in values.iter().enumerate() {
            assert_eq!(*v, f(p as u32 % w, p as u32 / w));
        }
        assert!(counts.computed < (w * h) as usize / 4, "{counts:?}");
    }

    #[test]
    fn pictures_of_any_size_are_covered() {
        for (w, h) in [(1, 1), (1, 7), (5, 1), (2, 2), (4, 4), (5, 9), (17, 3)] {
            let f = |x: u32, y: u32| Vec3::splat((x * 7 + y * 3) as f32);
            let (values, counts) = refined((w, h), f, |_, _, _| true);
            assert_eq!(counts.computed + counts.interpolated, (w * h) as usize);
            for (p, v) in values.iter().enumerate() {
                let exact = f(p as u32 % w, p as u32 / w);
                assert!((*v - exact).abs().max_element() < 1e-3, "{w}x{h} {p}");
            }
        }
    }

    /// A refinement begun inside another's `compute` on the same thread (as a rayon
    /// worker may, stealing another picture's work) keeps its own memory: both give
    /// what they give alone, and so does the next one, which reuses the memory.
    #[test]
    fn a_refinement_nested_on_the_same_thread_keeps_its_own_memory() {
        let inner = |x: u32, y: u32| Vec3::new(x as f32, 2.0 * y as f32, 1.0);
        let (alone, _) = refined((30, 20), inner, |_, _, _| true);
        let outer = |x: u32, y: u32| Vec3::splat(if 3 * x + y > 40 { 2.0 } else { 1.0 });
        let mut nested = Vec::new();
        let mut values = vec![Vec3::ZERO; 40 * 30];
        refine(
            (40, 30),
            TOLERANCE,
            |pixels, out| {
                if nested.is_empty() {
                    nested = refined((30, 20), inner, |_, _, _| true).0;
                }
                for (p, o) in pixels.iter().zip(out) {
                    *o = outer(p % 40, p / 40);
                }
            },
            |_, _, _| true,
            &mut values,
        );
        assert_eq!(nested, alone);
        assert_eq!(values, refined((40, 30), outer, |_, _, _| true).0);
        assert_eq!(refined((30, 20), inner, |_, _, _| true).0, alone);
    }
}
