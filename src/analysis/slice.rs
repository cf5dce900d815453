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
    let to_pixels = |k: usize, frame: &SliceFrame, x: f64, y: f64| {
        let (ox, oy) = origin(k);
        (
            ox + (x * scale).round() as i32,
            oy + ((frame.simbox.lengths[1] - y) * scale).round() as i32,
        )
    };
    // Discs that cross a periodic face are drawn at their images too; once
    // every frame is drawn, whatever lies outside its box is masked.
    for (k, frame) in frames.iter().enumerate() {
        let [lx, ly] = [frame.simbox.lengths[0], frame.simbox.lengths[1]];
        for disc in slice_discs(frame, diameter) {
            let r = (disc.radius * scale).max(0.5).round() as i32;
            for (ix, iy) in (-1..=1).flat_map(|i| (-1..=1).map(move |j| (i, j))) {
                let (x, y) = (disc.x + f64::from(ix) * lx, disc.y + f64::from(iy) * ly);
                let inside = x + disc.radius > 0.0
                    && x - disc.radius < lx
                    && y + disc.radius > 0.0
                    && y - disc.radius < ly;
                if inside {
                    let centre = to_pixels(k, frame, x, y);
                    root.draw(&Circle::new(centre, r, grain_colour(disc.grain).filled()))
                        .map_err(|e| err(e.to_string()))?;
                }
            }
        }
    }
    for (k, frame) in frames.iter().enumerate() {
        let [lx, ly] = [frame.simbox.lengths[0], frame.simbox.lengths[1]];
        let (left, top) = to_pixels(k, frame, 0.0, ly);
        let (right, bottom) = to_pixels(k, frame, lx, 0.0);
        // One pixel of overlap, so no seam shows between masks.
        let panel_left = (k as u32 * panel) as i32 - 1;
        let panel_right = ((k as u32 + 1) * panel) as i32 + 1;
        // Masks reach past the canvas, over images drawn beyond it.
        let height = (2 * panel + margin) as i32;
        for [a, b] in [
            [(panel_left, -height), (left, height)],
            [(right, -height), (panel_right, height)],
            [(left - 1, -height), (right + 1, top)],
            [(left - 1, bottom), (right + 1, height)],
        ] {
            root.draw(&Rectangle::new([a, b], WHITE.filled()))
                .map_err(|e| err(e.to_string()))?;
        }
        root.draw(&Rectangle::new(
            [(left, top), (right, bottom)],
            BLACK.stroke_width(1),
        ))
        .map_err(|e| err(e.to_string()))?;
        root.draw(&Text::new(
            frame.title.clone(),
            (origin(k).0, margin as i32 / 2),
            style.clone(),
        ))
        .map_err(|e| err(e.to_string()))?;
    }
    root.present().map_err(|e| err(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

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
