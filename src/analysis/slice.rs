//! Slice pictures of a packing: the particles cut by the plane `z = const`
//! through the middle of a periodic box, each drawn as its cross-section
//! disc and coloured by its grain, as SVG. Frames of one picture share a
//! scale, so a compressed box looks smaller than the loose one.

use super::plot::PlotError;
use crate::engine::SimBox;
use plotters::prelude::*;
use std::path::Path;

/// One frame: a packing state.
pub struct SliceFrame<'a> {
    /// Caption.
    pub title: String,
    /// The box (orthogonal).
    pub simbox: &'a SimBox,
    /// Particle positions, wrapped or not.
    pub positions: &'a [[f64; 3]],
    /// Grain of each particle.
    pub grain: &'a [u32],
}

/// A particle's cross-section in the slice: centre (in box coordinates
/// from the lower corner, wrapped) and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    /// x from the box's lower corner, in `[0, lx)`.
    pub x: f64,
    /// y from the box's lower corner, in `[0, ly)`.
    pub y: f64,
    /// Radius of the cut: `sqrt((d/2)^2 - dz^2)`.
    pub radius: f64,
    /// Grain of the particle.
    pub grain: u32,
}

/// The discs that the mid-box plane `z = lo_z + lz / 2` cuts from spheres
/// of diameter `diameter`, with `z` taken through the minimum image.
pub fn slice_discs(frame: &SliceFrame, diameter: f64) -> Vec<Disc> {
    let b = frame.simbox;
    let half = 0.5 * diameter;
    let plane = b.lo[2] + 0.5 * b.lengths[2];
    let wrap = |v: f64, lo: f64, l: f64| (v - lo).rem_euclid(l);
    frame
        .positions
        .iter()
        .zip(frame.grain)
        .filter_map(|(x, &grain)| {
            let mut dz = x[2] - plane;
            dz -= b.lengths[2] * (dz / b.lengths[2]).round();
            (dz.abs() < half).then(|| Disc {
                x: wrap(x[0], b.lo[0], b.lengths[0]),
                y: wrap(x[1], b.lo[1], b.lengths[1]),
                radius: (half * half - dz * dz).sqrt(),
                grain,
            })
        })
        .collect()
}

/// Sides of the polygon that draws a disc.
const DISC_SIDES: usize = 48;

/// The part of the disc at `centre` with `radius` inside the box `[0, lx]
/// x [0, ly]`, as a polygon (a regular `DISC_SIDES`-gon clipped against
/// each side of the box in turn; empty when they do not meet).
pub fn disc_in_box(centre: (f64, f64), radius: f64, lx: f64, ly: f64) -> Vec<(f64, f64)> {
    let mut polygon: Vec<(f64, f64)> = (0..DISC_SIDES)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / DISC_SIDES as f64;
            (centre.0 + radius * t.cos(), centre.1 + radius * t.sin())
        })
        .collect();
    // Each half-plane as (axis, bound, keep below the bound).
    for (axis, bound, below) in [
        (0, 0.0, false),
        (0, lx, true),
        (1, 0.0, false),
        (1, ly, true),
    ] {
        let coord = |p: (f64, f64)| if axis == 0 { p.0 } else { p.1 };
        let inside = |p: (f64, f64)| (coord(p) <= bound) == below || coord(p) == bound;
        let mut kept = Vec::with_capacity(polygon.len() + 2);
        for (i, &b) in polygon.iter().enumerate() {
            let a = polygon[(i + polygon.len() - 1) % polygon.len()];
            if inside(a) != inside(b) {
                let t = (bound - coord(a)) / (coord(b) - coord(a));
                kept.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
            }
            if inside(b) {
                kept.push(b);
            }
        }
        polygon = kept;
        if polygon.is_empty() {
            break;
        }
    }
    polygon
}

/// A colour per grain: hues spread by the golden angle, so neighbouring
/// grain ids differ clearly.
fn grain_colour(grain: u32) -> RGBColor {
    let hue = (f64::from(grain) * 0.618_033_988_749_895).fract();
    let [r, g, b] = hsl_to_rgb(hue, 0.65, 0.55);
    RGBColor(r, g, b)
}

fn hsl_to_rgb(h: f64, s: f64, l: f64) -> [u8; 3] {
    let c = (1.0 - (2.0 * l - 1.0).abs()) * s;
    let hp = h * 6.0;
    let x = c * (1.0 - (hp % 2.0 - 1.0).abs());
    let (r, g, b) = match hp as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    [r, g, b].map(|v| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8)
}

/// Writes the frames side by side into one SVG at a common scale (the
/// largest box fills its panel); particles of diameter `diameter`.
pub fn write_slices(path: &Path, frames: &[SliceFrame], diameter: f64) -> Result<(), PlotError> {
    let err = |e: String| PlotError::new(path, e);
    let panel = 480u32;
    let margin = 30u32;
    let extent = frames
        .iter()
        .map(|f| f.simbox.lengths[0].max(f.simbox.lengths[1]))
        .fold(0.0, f64::max);
    if frames.is_empty() || !(extent > 0.0 && extent.is_finite()) {
        return Err(err("no frame with a finite box to draw".into()));
    }
    let scale = f64::from(panel - 2 * margin) / extent;
    let root =
        SVGBackend::new(path, (panel * frames.len() as u32, panel + margin)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let style = TextStyle::from(("sans-serif", 16).into_font()).color(&BLACK);
    let origin = |k: usize| ((k as u32 * panel + margin) as i32, (2 * margin) as i32);
    for (k, frame) in frames.iter().enumerate() {
        let [lx, ly] = [frame.simbox.lengths[0], frame.simbox.lengths[1]];
        let (ox, oy) = origin(k);
        let px = |(x, y): (f64, f64)| {
            (
                ox + (x * scale).round() as i32,
                oy + ((ly - y) * scale).round() as i32,
            )
        };
        // A disc that crosses a periodic face shows at its images too; each
        // is cut to the box.
        for disc in slice_discs(frame, diameter) {
            for (ix, iy) in (-1..=1).flat_map(|i| (-1..=1).map(move |j| (i, j))) {
                let centre = (disc.x + f64::from(ix) * lx, disc.y + f64::from(iy) * ly);
                // At least half a pixel, so grazing cuts still show.
                let cut = disc_in_box(centre, disc.radius.max(0.5 / scale), lx, ly);
                if cut.len() >= 3 {
                    let points: Vec<(i32, i32)> = cut.into_iter().map(px).collect();
                    root.draw(&Polygon::new(points, grain_colour(disc.grain).filled()))
                        .map_err(|e| err(e.to_string()))?;
                }
            }
        }
        root.draw(&Rectangle::new(
            [px((0.0, ly)), px((lx, 0.0))],
            BLACK.stroke_width(1),
        ))
        .map_err(|e| err(e.to_string()))?;
        root.draw(&Text::new(
            frame.title.clone(),
            (ox, margin as i32 / 2),
            style.clone(),
        ))
        .map_err(|e| err(e.to_string()))?;
    }
    root.present().map_err(|e| err(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(polygon: &[(f64, f64)]) -> f64 {
        let n = polygon.len();
        0.5 * (0..n)
            .map(|i| {
                let (a, b) = (polygon[i], polygon[(i + 1) % n]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            .abs()
    }

    /// A disc inside the box is whole, one on a corner keeps a quarter, one
    /// across a face keeps its half, one outside vanishes.
    #[test]
    fn discs_are_cut_to_the_box() {
        let (lx, ly) = (10.0, 6.0);
        let whole = disc_in_box((5.0, 3.0), 1.0, lx, ly);
        let full = area(&whole);
        let sides = DISC_SIDES as f64;
        let expected = 0.5 * sides * (std::f64::consts::TAU / sides).sin();
        assert!((full - expected).abs() < 1e-12, "{full}");
        let corner = area(&disc_in_box((lx, ly), 1.0, lx, ly));
        assert!((corner - 0.25 * full).abs() < 1e-12, "{corner}");
        let face = area(&disc_in_box((0.0, 3.0), 1.0, lx, ly));
        assert!((face - 0.5 * full).abs() < 1e-12, "{face}");
        let overhang = disc_in_box((-0.5, 5.8), 1.0, lx, ly);
        assert!(area(&overhang) > 0.1 * full, "{}", area(&overhang));
        for p in overhang {
            assert!(p.0 >= 0.0 && p.0 <= lx && p.1 >= 0.0 && p.1 <= ly, "{p:?}");
        }
        assert!(disc_in_box((-2.0, 3.0), 1.0, lx, ly).is_empty());
    }

    #[test]
    fn the_mid_plane_cuts_the_right_discs_across_the_periodic_face() {
        let simbox = SimBox {
            lo: [-5.0, -5.0, -5.0],
            lengths: [10.0, 10.0, 10.0],
            tilt: [0.0; 3],
            periodic: [true; 3],
        };
        // On the plane; 0.3 below it; 0.6 above it (no cut); an image
        // across x's periodic face, 0.4 from the plane.
        let positions = [
            [0.0, 0.0, 0.0],
            [1.0, 2.0, -0.3],
            [2.0, 2.0, 0.6],
            [5.5, -4.0, 10.4],
        ];
        let grain = [0, 1, 2, 3];
        let frame = SliceFrame {
            title: String::new(),
            simbox: &simbox,
            positions: &positions,
            grain: &grain,
        };
        let discs = slice_discs(&frame, 1.0);
        assert_eq!(discs.len(), 3);
        assert!((discs[0].radius - 0.5).abs() < 1e-15);
        assert!((discs[1].radius - (0.25f64 - 0.09).sqrt()).abs() < 1e-15);
        assert_eq!(discs[2].grain, 3);
        assert!((discs[2].x - 0.5).abs() < 1e-12 && (discs[2].y - 1.0).abs() < 1e-12);
        assert!((discs[2].radius - (0.25f64 - 0.16).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn hues_cover_the_colour_wheel() {
        assert_eq!(hsl_to_rgb(0.0, 1.0, 0.5), [255, 0, 0]);
        assert_eq!(hsl_to_rgb(1.0 / 3.0, 1.0, 0.5), [0, 255, 0]);
        assert_eq!(hsl_to_rgb(2.0 / 3.0, 1.0, 0.5), [0, 0, 255]);
    }
}
