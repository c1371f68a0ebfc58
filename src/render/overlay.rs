//! Lines drawn over particle images: the Roche lobes of a binary run.
//!
//! A run of a binary (a `[binary]` table in its problem file) is simulated in the frame of
//! `analysis::roche` — accretor at the origin, donor at (−1, 0, 0), separation a = 1 — which
//! turns with the binary, so the lobes stand still in every snapshot. The outline of each
//! star's lobe (the critical equipotential Φ = Φ_L1, [`roche::lobe_outline`]) is drawn in
//! the orbital plane for face-on views and slices and in the meridional plane for edge-on
//! views — each cut is also the outline of the lobe projected onto its plane — as thin
//! white lines, together the paper's figure eight (Figures 5 and 6), and L1 is marked with a
//! small cross.
//!
//! The mass ratio comes from the snapshot's `/Parameters` ([`mass_ratio`]): `binary:q`, or
//! `binary:m2_msun / binary:m1_msun`. Lines are rasterised here pixel by pixel (Bresenham,
//! not anti-aliased) with the image's own pixel mapping: the field pixel that shows a point
//! is the pixel the line passes through, and every line pixel has exactly [`OVERLAY_RGB`].

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

use anyhow::{Result, anyhow, bail};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::analysis::roche::{self, Plane};
use crate::io::hdf5::read_parameters;
use crate::io::snapshot_index::snapshot_of;
use crate::render::interpolate::{Frame, View};

/// The colour of the overlay lines (white: no colour map reaches it).
pub const OVERLAY_RGB: [u8; 3] = [255, 255, 255];

/// Rays per lobe outline: at 2400 screen pixels across a lobe, about one point per 3 pixels.
const OUTLINE_RAYS: usize = 2048;

/// Half the length of the arms of the cross at L1, in screen pixels.
const CROSS_ARM: i32 = 5;

/// The mass ratio q = M2/M1 of a binary run from its snapshot parameters (keys as
/// [`read_parameters`] gives them): `binary:q`, else `binary:m2_msun / binary:m1_msun`;
/// `None` when the run is not a binary. A value that is not a positive number is an error.
pub fn mass_ratio(parameters: &BTreeMap<String, String>) -> Result<Option<f64>> {
    let number = |key: &str| -> Result<Option<f64>> {
        let Some(text) = parameters.get(key) else {
            return Ok(None);
        };
        match text.trim().trim_matches('"').parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(Some(x)),
            _ => bail!("parameter {key} = {text:?} is not a positive number"),
        }
    };
    if let Some(q) = number("binary:q")? {
        return Ok(Some(q));
    }
    match (number("binary:m1_msun")?, number("binary:m2_msun")?) {
        (Some(m1), Some(m2)) => Ok(Some(m2 / m1)),
        _ => Ok(None),
    }
}

/// The mass ratio of the binary run behind `input` — a snapshot, or a run folder (its first
/// snapshot in `snapshots.json`) — as [`mass_ratio`]; `None` when it is not a binary.
pub fn mass_ratio_of(input: &Path) -> Result<Option<f64>> {
    let Some(snapshot) = snapshot_of(input)? else {
        return Ok(None);
    };
    mass_ratio(&read_parameters(&snapshot)?)
        .map_err(|e| anyhow!("{}: {e} (render with --no-roche)", snapshot.display()))
}

/// The plane of `view`'s image for the lobe outlines.
fn plane_of(view: View) -> Plane {
    match view {
        View::EdgeOn => Plane::Meridional,
        View::FaceOn | View::Slice => Plane::Orbital,
    }
}

/// The lobe outlines (accretor's, donor's; closed polylines) and L1 in the image plane of
/// `view`, in the coordinates of a snapshot whose positions are the run's plus `shift`
/// (`Snapshot::shift`; zero after `Snapshot::in_run_frame`).
pub fn roche_curves(q: f64, view: View, shift: [f64; 3]) -> ([Vec<[f64; 2]>; 2], [f64; 2]) {
    let plane = plane_of(view);
    let b = match plane {
        Plane::Orbital => 1,
        Plane::Meridional => 2,
    };
    let moved = |c: Vec<[f64; 2]>| -> Vec<[f64; 2]> {
        c.into_iter()
            .map(|p| [p[0] + shift[0], p[1] + shift[b]])
            .collect()
    };
    let lobes =
        [false, true].map(|donor| moved(roche::lobe_outline(q, donor, plane, OUTLINE_RAYS)));
    let l1 = roche::l1_point(q);
    (lobes, [l1[0] + shift[0], l1[b] + shift[b]])
}

/// Where the image of `frame` lies on the screen: the plot area's pixel ranges (x to the
/// right, y downwards), filled by the field as `image::draw_on` fills it — field column i
/// covers x₀ + [i, i+1) Δx and shows on screen columns [i, i+1) w/nx from the left, field row j
/// likewise from the bottom — so the point (x, y) shows on plot pixel
/// (⌊(x − x₀)/(x₁ − x₀) · w⌋, ⌊(y − y₀)/(y₁ − y₀) · h⌋), counted from the bottom left.
#[derive(Clone, Debug)]
pub struct PixelMap {
    pub frame: Frame,
    pub px: Range<i32>,
    pub py: Range<i32>,
}

impl PixelMap {
    /// Plot width and height in screen pixels.
    fn size(&self) -> [f64; 2] {
        [
            f64::from(self.px.end - self.px.start),
            f64::from(self.py.end - self.py.start),
        ]
    }

    /// The point (x, y) in continuous plot pixels from the bottom left corner.
    pub fn to_plot(&self, p: [f64; 2]) -> [f64; 2] {
        let (x, y) = (self.frame.x, self.frame.y);
        let [w, h] = self.size();
        [
            (p[0] - x.0) / (x.1 - x.0) * w,
            (p[1] - y.0) / (y.1 - y.0) * h,
        ]
    }

    /// The screen pixel of the plot pixel (i, j) counted from the bottom left.
    fn screen(&self, (i, j): (i32, i32)) -> (i32, i32) {
        (self.px.start + i, self.py.end - 1 - j)
    }

    /// Whether the plot pixel (i, j) lies in the image.
    fn inside(&self, (i, j): (i32, i32)) -> bool {
        (0..self.px.end - self.px.start).contains(&i)
            && (0..self.py.end - self.py.start).contains(&j)
    }

    /// The screen pixel showing (x, y), if it lies in the image.
    pub fn pixel(&self, p: [f64; 2]) -> Option<(i32, i32)> {
        let [u, v] = self.to_plot(p);
        let [w, h] = self.size();
        let inside = (0.0..w).contains(&u) && (0.0..h).contains(&v);
        inside.then(|| self.screen((u.floor() as i32, v.floor() as i32)))
    }

    /// The screen pixels of the segment a–b (both in plot pixels, [`Self::to_plot`]) inside
    /// the image: the segment clipped to the image (Liang–Barsky), then Bresenham between the
    /// pixels of its ends.
    fn segment_pixels(&self, a: [f64; 2], b: [f64; 2], out: &mut Vec<(i32, i32)>) {
        // Just inside the far edges, so that ⌊·⌋ stays in the image.
        let [w, h] = self.size();
        let hi = [w - 1e-9, h - 1e-9];
        let d = [b[0] - a[0], b[1] - a[1]];
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..2 {
            for (p, q) in [(-d[k], a[k]), (d[k], hi[k] - a[k])] {
                if p == 0.0 {
                    if q < 0.0 {
                        return;
                    }
                } else {
                    let t = q / p;
                    if p < 0.0 {
                        t0 = t0.max(t);
                    } else {
                        t1 = t1.min(t);
                    }
                }
            }
        }
        if !(t0 <= t1) {
            return;
        }
        let at = |t: f64| {
            (
                (a[0] + t * d[0]).floor() as i32,
                (a[1] + t * d[1]).floor() as i32,
            )
        };
        let ((mut x, mut y), (x1, y1)) = (at(t0), at(t1));
        let (dx, dy) = ((x1 - x).abs(), -(y1 - y).abs());
        let (sx, sy) = ((x1 - x).signum(), (y1 - y).signum());
        let mut err = dx + dy;
        loop {
            if self.inside((x, y)) {
                out.push(self.screen((x, y)));
            }
            if x == x1 && y == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }
}

/// The screen pixels of the Roche overlay for mass ratio `q` on the image `map` of `view`:
/// both lobe outlines, and the cross at L1 when L1 is in the image.
pub fn roche_pixels(q: f64, view: View, shift: [f64; 3], map: &PixelMap) -> Vec<(i32, i32)> {
    let (lobes, l1) = roche_curves(q, view, shift);
    let mut out = Vec::new();
    for lobe in &lobes {
        for pair in lobe.windows(2) {
            map.segment_pixels(map.to_plot(pair[0]), map.to_plot(pair[1]), &mut out);
        }
    }
    if let Some((c, r)) = map.pixel(l1) {
        for k in -CROSS_ARM..=CROSS_ARM {
            for p in [(c + k, r), (c, r + k)] {
                if map.px.contains(&p.0) && map.py.contains(&p.1) {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// Draws the Roche overlay for mass ratio `q` onto `root` (the whole picture) over the image
/// `map` of `view`, in [`OVERLAY_RGB`].
pub fn draw_roche<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    q: f64,
    view: View,
    shift: [f64; 3],
    map: &PixelMap,
) -> Result<()> {
    let colour = RGBColor(OVERLAY_RGB[0], OVERLAY_RGB[1], OVERLAY_RGB[2]);
    for p in roche_pixels(q, view, shift, map) {
        root.draw_pixel(p, &colour)
            .map_err(|e| anyhow!("cannot draw the Roche lobes: {e}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::interpolate::Extent;

    #[test]
    fn mass_ratio_from_q_or_the_masses() {
        let params = |kv: &[(&str, &str)]| -> BTreeMap<String, String> {
            kv.iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        assert_eq!(mass_ratio(&params(&[])).unwrap(), None);
        assert_eq!(
            mass_ratio(&params(&[("binary:q", "0.1"), ("eos:gamma", "1.4")])).unwrap(),
            Some(0.1)
        );
        let m = mass_ratio(&params(&[
            ("binary:m1_msun", "0.696"),
            ("binary:m2_msun", "0.069"),
        ]))
        .unwrap()
        .unwrap();
        assert!((m - 0.069 / 0.696).abs() < 1e-15);
        assert!(mass_ratio(&params(&[("binary:q", "-1")])).is_err());
        assert!(mass_ratio(&params(&[("binary:q", "abc")])).is_err());
    }

    #[test]
    fn segments_are_clipped_to_the_image_and_connected() {
        let frame = Frame::new(Extent::new((0.0, 1.0), (0.0, 1.0)).unwrap(), 10, 10);
        let map = PixelMap {
            frame,
            px: 100..200,
            py: 50..150,
        };
        // (0, 0) is the bottom left corner: column 100, row 149.
        assert_eq!(map.pixel([0.0, 0.0]), Some((100, 149)));
        assert_eq!(map.pixel([0.999, 0.999]), Some((199, 50)));
        assert_eq!(map.pixel([1.0, 0.5]), None);
        // A diagonal through the whole image and beyond: one pixel per column, all inside.
        let mut px = Vec::new();
        map.segment_pixels(map.to_plot([-1.0, -1.0]), map.to_plot([2.0, 2.0]), &mut px);
        assert_eq!(px.len(), 100);
        assert!(
            px.windows(2)
                .all(|w| (w[1].0 - w[0].0).abs() <= 1 && (w[1].1 - w[0].1).abs() <= 1)
        );
        assert!(
            px.iter()
                .all(|p| map.px.contains(&p.0) && map.py.contains(&p.1))
        );
        // Entirely outside: nothing.
        px.clear();
        map.segment_pixels(map.to_plot([-1.0, 2.0]), map.to_plot([3.0, 2.0]), &mut px);
        assert!(px.is_empty());
    }

    #[test]
    fn curves_follow_the_view_and_the_shift() {
        let q = 0.2;
        let d = roche::l1_distance(q);
        let ([acc, don], l1) = roche_curves(q, View::EdgeOn, [3.0, 4.0, 5.0]);
        assert_eq!(l1, [3.0 - d, 5.0]);
        assert_eq!(acc[0], l1);
        assert_eq!(don[0], l1);
        // The accretor's lobe reaches farther to the right than its star, the donor's less
        // far to the left.
        assert!(acc.iter().all(|p| p[0] >= 3.0 - d) && don.iter().all(|p| p[0] <= 3.0 - d));
    }
}
