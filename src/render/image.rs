//! Particle images as PNG: a snapshot's interpolated field drawn pixel for pixel inside a chart
//! with axes in code units (cm with a run's physical units), a colour bar labelled with the quantity (and log10 on a log
//! scale), point masses marked, the Roche lobes of a binary run drawn over it (`overlay`),
//! and a title with the time; plus the colour ranges that movie frames share.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::io::hdf5::Units;
use crate::io::snapshot::Snapshot;
use crate::render::colormap::{ColorRange, Colormap, Scale};
use crate::render::interpolate::{
    Extent, Frame, Quantity, View, interpolate_counted, with_periodic_images,
};
use crate::render::overlay::{PixelMap, draw_roche};
use crate::render::plot::ensure_font;

/// What to draw and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub quantity: Quantity,
    pub view: View,
    pub scale: Scale,
    pub colormap: Colormap,
    /// The largest pixel grid of the field, (nx, ny). Pixels are square: the frame's side that
    /// is shorter relative to this gets fewer pixels. The PNG repeats each field pixel over
    /// k × k screen pixels (k ≥ 1) so that small grids still give a readable picture.
    pub resolution: (u32, u32),
    /// Fixed colour range (movies); `None`: from this image (see [`common_range`]).
    pub range: Option<(f64, f64)>,
    /// The rectangle shown, along the view's axes; `None`: the box (see [`Extent::default_for`]).
    pub frame: Option<Extent>,
    /// Height of the slice plane (3D slices); `None`: the middle of the box.
    pub slice_z: Option<f64>,
    /// Title; `None`: the quantity and the view. The time is always appended.
    pub title: Option<String>,
    /// The mass ratio q of a binary whose Roche lobes (both outlines and L1, in the frame of
    /// `analysis::roche`) are drawn over the image; `None`: no lobes. `sphdisk render` takes
    /// it from the snapshot's parameters ([`crate::render::overlay::mass_ratio_of`]).
    pub roche_q: Option<f64>,
    /// The run's physical units (`[units]`, or a binary's masses and period): axes and
    /// colour bar in cgs (K for the temperature); `None`: code units.
    /// `sphdisk render` reads them from the snapshot ([`crate::io::hdf5::read_units`]).
    pub units: Option<Units>,
    /// The box is periodic: particles near its faces are also drawn at their periodic
    /// images ([`with_periodic_images`]).
    pub periodic: bool,
}

impl RenderOptions {
    /// Defaults for `quantity` seen from `view`: its usual scale and colour map, 512 × 512.
    pub fn new(quantity: Quantity, view: View) -> Self {
        Self {
            quantity,
            view,
            scale: quantity.default_scale(),
            colormap: quantity.default_colormap(),
            resolution: (512, 512),
            range: None,
            frame: None,
            slice_z: None,
            title: None,
            roche_q: None,
            units: None,
            periodic: false,
        }
    }
}

/// The field behind a PNG (row-major from the bottom row, see [`Frame`]), its grid, and the
/// colour range it was drawn with.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedImage {
    pub field: Vec<f64>,
    pub frame: Frame,
    pub range_used: (f64, f64),
}

/// The extent shown when `opts` gives none: the particles' ([`Extent::default_for`]); for
/// a binary whose Roche lobes are drawn, the box (a cv run's box is sized to the binary),
/// so that the lobes are in the picture.
pub fn default_extent(snap: &Snapshot, opts: &RenderOptions) -> Result<Extent> {
    if opts.roche_q.is_some() {
        Extent::of_box(snap, opts.view)
    } else {
        Extent::default_for(snap, opts.view)
    }
}

/// The grid of `opts` for `snap`: the chosen or default extent at the requested resolution.
pub fn frame_for(snap: &Snapshot, opts: &RenderOptions) -> Result<Frame> {
    let extent = match opts.frame {
        Some(e) => Extent::new(e.x, e.y)?,
        None => default_extent(snap, opts)?,
    };
    let frame = Frame::fit(
        extent,
        (opts.resolution.0 as usize, opts.resolution.1 as usize),
    );
    frame.check()?;
    Ok(frame)
}

/// Interpolates the field of `opts` without drawing it (movies: fields first, one range);
/// also returns how many particles reach the frame.
pub fn render_field(snap: &Snapshot, opts: &RenderOptions) -> Result<(Vec<f64>, Frame, usize)> {
    let frame = frame_for(snap, opts)?;
    let (field, reached) = if opts.periodic {
        let imaged = with_periodic_images(snap, opts.view);
        interpolate_counted(&imaged, opts.quantity, opts.view, &frame, opts.slice_z)?
    } else {
        interpolate_counted(snap, opts.quantity, opts.view, &frame, opts.slice_z)?
    };
    Ok((field, frame, reached))
}

/// The refusal of a picture no particle reaches: a blank field has no colour range, and
/// one invented for it would draw nothing as if it were something.
pub fn nothing_to_draw(snap: &Snapshot, opts: &RenderOptions, frame: &Frame) -> anyhow::Error {
    if snap.is_empty() {
        return anyhow!("the snapshot holds no particles: nothing to draw");
    }
    let slice = if opts.view == View::Slice && snap.dimension == 3 {
        " or the slice z = ".to_string()
            + &opts
                .slice_z
                .map_or("middle of the box".into(), |z| format!("{z}"))
    } else {
        String::new()
    };
    anyhow!(
        "none of its {} particles reaches the frame x ∈ [{}, {}], y ∈ [{}, {}]{slice}: \
         nothing to draw (--xlim, --ylim)",
        snap.len(),
        frame.x.0,
        frame.x.1,
        frame.y.0,
        frame.y.1
    )
}

/// Interpolates and draws `snap` as `opts` says into the PNG `path` (written atomically).
pub fn render_png(snap: &Snapshot, opts: &RenderOptions, path: &Path) -> Result<RenderedImage> {
    if path.is_dir() {
        bail!(
            "{} is a folder: give the PNG file to write (e.g. {})",
            path.display(),
            path.join("picture.png").display()
        );
    }
    let (field, frame, reached) = render_field(snap, opts)?;
    if reached == 0 {
        return Err(nothing_to_draw(snap, opts, &frame));
    }
    let range_used = draw_png(snap, &field, &frame, opts, path)?;
    Ok(RenderedImage {
        field,
        frame,
        range_used,
    })
}

/// A colour range covering all `fields`: linear, min .. max of the finite values; log, from
/// the 1% quantile of the positive values (zeros and negatives ignored) to their maximum,
/// at most [`LOG_DECADES`] decades — so that a field within a factor of a few (a blast's
/// shell over its background in column density) spans the colours instead of filling their
/// top tenth. Degenerate ranges are widened so that they can be drawn.
pub fn common_range(fields: &[&[f64]], scale: Scale) -> (f64, f64) {
    let values = || fields.iter().flat_map(|f| f.iter().copied());
    match scale {
        Scale::Linear => {
            let (lo, hi) = values()
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                });
            if !(lo <= hi) {
                (0.0, 1.0)
            } else if lo < hi {
                (lo, hi)
            } else {
                let pad = if lo == 0.0 { 1.0 } else { 0.5 * lo.abs() };
                (lo - pad, hi + pad)
            }
        }
        Scale::Log => {
            let mut positive: Vec<f64> = values().filter(|v| v.is_finite() && *v > 0.0).collect();
            if positive.is_empty() {
                return (10f64.powi(-LOG_DECADES), 1.0);
            }
            positive.sort_by(f64::total_cmp);
            let hi = positive[positive.len() - 1];
            let low_quantile = positive[(positive.len() - 1) / 100];
            let lo = low_quantile.max(hi * 10f64.powi(-LOG_DECADES));
            if lo < hi {
                (lo, hi)
            } else {
                (hi / 10.0, hi * 10.0)
            }
        }
    }
}

/// The most decades an automatic log colour range spans.
pub const LOG_DECADES: i32 = 4;

/// Layout of the picture, in screen pixels.
const TITLE_H: u32 = 40;
const MARGIN: u32 = 15;
const X_LABEL_AREA: u32 = 50;
const Y_LABEL_AREA: u32 = 80;
const BAR_GAP: u32 = 10;
const BAR_W: u32 = 24;
const BAR_LABEL_AREA: u32 = 95;
/// The plot's longer side is scaled up to at least this, its shorter side to at least
/// `MIN_SHORT`, but the longer side never beyond `MAX_LONG` by scaling.
const MIN_LONG: usize = 500;
const MIN_SHORT: usize = 200;
const MAX_LONG: usize = 2400;

/// Screen pixels per field pixel along each axis.
fn upscale(nx: usize, ny: usize) -> usize {
    let (long, short) = (nx.max(ny), nx.min(ny));
    let want = MIN_LONG.div_ceil(long).max(MIN_SHORT.div_ceil(short));
    want.min((MAX_LONG / long).max(1)).max(1)
}

/// A tick label: plain decimals for moderate magnitudes, otherwise scientific.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e4).contains(&a) {
        let s = format!("{v:.2e}");
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Tick labels for an axis spanning `span`: rounding residues of zero (−2.8e−17) read 0.
fn ticks_for(span: f64) -> impl Fn(&f64) -> String {
    move |v: &f64| {
        if v.abs() < 1e-9 * span {
            "0".into()
        } else {
            tick(v)
        }
    }
}

/// The time in a title: four significant decimals or scientific notation.
fn format_time(t: f64) -> String {
    if t == 0.0 || (1e-3..1e5).contains(&t.abs()) {
        format!("{t:.4}")
    } else {
        format!("{t:.4e}")
    }
}

fn default_title(snap: &Snapshot, opts: &RenderOptions) -> String {
    let q = opts.quantity;
    let where_ = match (snap.dimension, opts.view) {
        (2, _) => "2D plane".to_string(),
        (_, View::Slice) => {
            let z = opts
                .slice_z
                .unwrap_or(0.5 * (snap.box_lo[2] + snap.box_hi[2]));
            format!("slice z = {}", tick(&z))
        }
        (_, v) if q == Quantity::ColumnDensity => format!("{v}"),
        (_, v) => format!("{v}, column-weighted along {}", los_axis(v)),
    };
    format!("{}, {where_}", quantity_label(opts))
}

/// The quantity's name in the title and on the colour bar: with physical units the
/// temperature is T in K, not P/ρ.
fn quantity_label(opts: &RenderOptions) -> &'static str {
    match (opts.quantity, &opts.units) {
        (Quantity::Temperature, Some(_)) => "T (temperature)",
        (q, _) => q.label(),
    }
}

fn los_axis(view: View) -> &'static str {
    match view {
        View::EdgeOn => "y",
        _ => "z",
    }
}

/// Draws `field` on `frame` into the PNG `path` (atomically: a temporary file beside it,
/// renamed); returns the colour range used (`opts.range`, or [`common_range`] of the field).
pub fn draw_png(
    snap: &Snapshot,
    field: &[f64],
    frame: &Frame,
    opts: &RenderOptions,
    path: &Path,
) -> Result<(f64, f64)> {
    if field.len() != frame.len() {
        bail!(
            "field has {} values for a {} × {} frame",
            field.len(),
            frame.nx,
            frame.ny
        );
    }
    let (lo, hi) = opts
        .range
        .unwrap_or_else(|| common_range(&[field], opts.scale));
    let range = ColorRange::new(lo, hi, opts.scale)?;
    let tmp = temporary_png(path)?;
    let result = draw_to(snap, field, frame, opts, range, &tmp)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(anyhow::Error::from));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("cannot write {}", path.display()))?;
    Ok((lo, hi))
}

/// `.name.tmp-PID.png` beside `path`: plotters picks the encoder by the extension.
fn temporary_png(path: &Path) -> Result<PathBuf> {
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    Ok(dir.join(format!(
        ".{}.tmp-{}.png",
        name.to_string_lossy(),
        std::process::id()
    )))
}

/// Size of the picture of `frame`, in screen pixels, and the field-pixel scale factor k.
fn picture_size(frame: &Frame) -> ((u32, u32), u32) {
    let k = upscale(frame.nx, frame.ny);
    let (plot_w, plot_h) = ((frame.nx * k) as u32, (frame.ny * k) as u32);
    let left_w = 2 * MARGIN + Y_LABEL_AREA + plot_w;
    let bar_total = BAR_GAP + BAR_W + BAR_LABEL_AREA + MARGIN;
    (
        (
            left_w + bar_total,
            TITLE_H + 2 * MARGIN + X_LABEL_AREA + plot_h,
        ),
        left_w,
    )
}

fn draw_to(
    snap: &Snapshot,
    field: &[f64],
    frame: &Frame,
    opts: &RenderOptions,
    range: ColorRange,
    path: &Path,
) -> Result<()> {
    let (size, _) = picture_size(frame);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    draw_on(&root, snap, field, frame, opts, range)?;
    // plotters' error prints the encoder's debug text: say what failed instead.
    root.present()
        .map_err(|_| anyhow!("the PNG encoder could not write the file"))?;
    Ok(())
}

/// Draws the picture onto `root`, which is [`picture_size`] large.
fn draw_on<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    snap: &Snapshot,
    field: &[f64],
    frame: &Frame,
    opts: &RenderOptions,
    range: ColorRange,
) -> Result<()> {
    ensure_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw: {e}");
    let (_, left_w) = picture_size(frame);
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (top, body) = root.split_vertically(TITLE_H);
    let (left, right) = body.split_horizontally(left_w);

    let title = format!(
        "{}   t = {}",
        opts.title
            .clone()
            .unwrap_or_else(|| default_title(snap, opts)),
        format_time(snap.time)
    );
    let (tw, th) = top.dim_in_pixel();
    top.draw(&Text::new(
        title,
        (tw as i32 / 2, th as i32 / 2),
        ("sans-serif", 20)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center)),
    ))
    .map_err(|e| err(&e))?;

    // The image, one field pixel per k × k screen pixels.
    let (xa, ya) = opts.view.axes();
    // Lengths in cm with physical units: the chart's coordinates are cgs, so that its ticks
    // fall on round values in cm.
    let (length, length_unit) = match &opts.units {
        Some(u) => (u.length_cgs, "cm"),
        None => (1.0, "code units"),
    };
    let mut chart = ChartBuilder::on(&left)
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(
            frame.x.0 * length..frame.x.1 * length,
            frame.y.0 * length..frame.y.1 * length,
        )
        .map_err(|e| err(&e))?;
    let (px, py) = chart.plotting_area().get_pixel_range();
    let (w, h) = ((px.end - px.start) as usize, (py.end - py.start) as usize);
    let mut buf = vec![0u8; 3 * w * h];
    for r in 0..h {
        // Screen rows run downwards, field rows upwards.
        let j = frame.ny - 1 - ((r * frame.ny) / h).min(frame.ny - 1);
        for c in 0..w {
            let i = ((c * frame.nx) / w).min(frame.nx - 1);
            let rgb = opts.colormap.rgb(range.t(field[j * frame.nx + i]));
            buf[3 * (r * w + c)..3 * (r * w + c) + 3].copy_from_slice(&rgb);
        }
    }
    let bitmap = BitMapElement::with_owned_buffer((px.start, py.start), (w as u32, h as u32), buf)
        .ok_or_else(|| anyhow!("image buffer does not match the plot area"))?;
    root.draw(&bitmap).map_err(|e| err(&e))?;
    let x_label = ticks_for(length * (frame.x.1 - frame.x.0));
    let y_label = ticks_for(length * (frame.y.1 - frame.y.0));
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(format!("{xa} ({length_unit})"))
        .y_desc(format!("{ya} ({length_unit})"))
        .x_label_formatter(&x_label)
        .y_label_formatter(&y_label)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| err(&e))?;

    // Point masses (the central star, binaries) inside the frame: white rings.
    let (ia, ib) = match opts.view {
        View::EdgeOn => (0, 2),
        _ => (0, 1),
    };
    let inside = |p: &[f64; 3]| {
        (frame.x.0..=frame.x.1).contains(&p[ia]) && (frame.y.0..=frame.y.1).contains(&p[ib])
    };
    chart
        .draw_series(
            snap.point_masses
                .iter()
                .filter(|pm| inside(&pm.pos))
                .map(|pm| {
                    let at = (pm.pos[ia] * length, pm.pos[ib] * length);
                    Circle::new(at, 5, WHITE.stroke_width(2))
                }),
        )
        .map_err(|e| err(&e))?;

    // A binary's Roche lobes and L1, on top, with the image's own pixel mapping.
    if let Some(q) = opts.roche_q {
        let map = PixelMap {
            frame: *frame,
            px,
            py,
        };
        draw_roche(root, q, opts.view, snap.shift, &map)?;
    }

    // The colour bar, level with the image.
    let (a_lo, a_hi) = (range.axis_value(range.lo), range.axis_value(range.hi));
    // With physical units the bar's values are cgs: × the factor, or + its log10; the
    // bar's coordinates are cgs, so that its ticks fall on round values.
    let (factor, unit) = match &opts.units {
        Some(u) => opts.quantity.cgs(snap.dimension, u),
        None => (1.0, opts.quantity.unit(snap.dimension).to_string()),
    };
    let to_cgs = |v: f64| match range.scale {
        Scale::Log => v + factor.log10(),
        Scale::Linear => v * factor,
    };
    let (c_lo, c_hi) = (to_cgs(a_lo), to_cgs(a_hi));
    let mut bar = ChartBuilder::on(&right)
        .margin_top(MARGIN)
        .margin_bottom(MARGIN + X_LABEL_AREA)
        .margin_left(BAR_GAP)
        .margin_right(MARGIN)
        .right_y_label_area_size(BAR_LABEL_AREA)
        .build_cartesian_2d(0.0..1.0, c_lo..c_hi)
        .map_err(|e| err(&e))?;
    let (bx, by) = bar.plotting_area().get_pixel_range();
    let (bw, bh) = ((bx.end - bx.start) as usize, (by.end - by.start) as usize);
    let mut bbuf = vec![0u8; 3 * bw * bh];
    for r in 0..bh {
        let rgb = opts.colormap.rgb(1.0 - (r as f64 + 0.5) / bh as f64);
        for c in 0..bw {
            bbuf[3 * (r * bw + c)..3 * (r * bw + c) + 3].copy_from_slice(&rgb);
        }
    }
    let bar_bitmap =
        BitMapElement::with_owned_buffer((bx.start, by.start), (bw as u32, bh as u32), bbuf)
            .ok_or_else(|| anyhow!("colour-bar buffer does not match its area"))?;
    root.draw(&bar_bitmap).map_err(|e| err(&e))?;
    let log = if range.scale == Scale::Log {
        "log10 "
    } else {
        ""
    };
    let label = quantity_label(opts);
    let bar_label = ticks_for(c_hi - c_lo);
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(format!("{log}{} [{unit}]", label))
        .y_label_formatter(&bar_label)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::snapshot::PointMassRecord;
    use crate::rng::Rng;

    /// A small 3D disk-like cloud about the origin with a central point mass.
    fn cloud(dimension: usize) -> Snapshot {
        let mut rng = Rng::new(3);
        let n = 800;
        let mut s = Snapshot {
            dimension,
            time: 12.5,
            box_lo: [-1.0; 3],
            box_hi: [1.0; 3],
            ..Snapshot::default()
        };
        for k in 0..n {
            let r = 0.2 + 0.6 * rng.uniform();
            let phi = std::f64::consts::TAU * rng.uniform();
            let z = if dimension == 3 {
                0.05 * rng.normal()
            } else {
                0.0
            };
            let p = [r * phi.cos(), r * phi.sin(), z];
            let v = [-phi.sin() / r.sqrt(), phi.cos() / r.sqrt(), 0.0];
            for d in 0..3 {
                s.pos[d].push(p[d]);
                s.vel[d].push(v[d]);
            }
            s.id.push(k as u64);
            s.mass.push(1.0 / n as f64);
            s.h.push(0.04);
            s.rho.push(1.0 / r);
            s.u.push(0.01 / r);
            s.p.push(0.01);
            s.diss.push(1e-3 * r);
        }
        s.point_masses.push(PointMassRecord {
            mass: 1.0,
            ..PointMassRecord::default()
        });
        s
    }

    /// Width and height from a PNG's IHDR chunk.
    fn png_size(bytes: &[u8]) -> (u32, u32) {
        let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
        (be(&bytes[16..20]), be(&bytes[20..24]))
    }

    #[test]
    fn render_png_writes_a_png() {
        let dir = tempfile::tempdir().unwrap();
        let cases = [
            (3, Quantity::ColumnDensity, View::FaceOn),
            (3, Quantity::Temperature, View::EdgeOn),
            (3, Quantity::Velocity, View::Slice),
            (2, Quantity::Density, View::FaceOn),
            (2, Quantity::Dissipation, View::Slice),
        ];
        for (k, (dim, q, v)) in cases.into_iter().enumerate() {
            let snap = cloud(dim);
            let mut opts = RenderOptions::new(q, v);
            opts.resolution = (96, 64);
            if k == 1 {
                opts.frame = Some(Extent::new((-1.0, 1.0), (-0.25, 0.25)).unwrap());
                opts.title = Some("edge-on".into());
            }
            let path = dir.path().join(format!("{k}.png"));
            let img = render_png(&snap, &opts, &path).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
            assert!(bytes.len() > 2000, "{} bytes", bytes.len());
            assert_eq!(png_size(&bytes), picture_size(&img.frame).0);
            assert_eq!(img.field.len(), img.frame.len());
            assert!(img.field.iter().any(|&v| v > 0.0));
            if opts.scale == Scale::Log {
                let max = img.field.iter().copied().fold(0.0, f64::max);
                assert_eq!(img.range_used, (max * 1e-4, max));
            }
        }
        // Only the pictures: no temporary file left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), cases.len());
        // A fixed range is used as given; an impossible one is refused.
        let snap = cloud(3);
        let mut opts = RenderOptions::new(Quantity::ColumnDensity, View::FaceOn);
        opts.resolution = (32, 32);
        opts.range = Some((1e-3, 10.0));
        let img = render_png(&snap, &opts, &dir.path().join("fixed.png")).unwrap();
        assert_eq!(img.range_used, (1e-3, 10.0));
        opts.range = Some((0.0, 10.0));
        assert!(render_png(&snap, &opts, &dir.path().join("bad.png")).is_err());
        assert!(!dir.path().join("bad.png").exists());
        let mut flat = cloud(3);
        flat.dimension = 1;
        assert!(render_png(&flat, &opts, &dir.path().join("1d.png")).is_err());
    }

    #[test]
    fn picture_puts_the_first_row_at_the_bottom() {
        // A field rising with the row index: the top of the plot takes the top colour, the
        // bottom the bottom colour; a field rising with the column: left bottom, right top.
        let snap = cloud(3);
        let frame = Frame::new(Extent::new((0.0, 1.0), (0.0, 1.0)).unwrap(), 50, 50);
        let mut opts = RenderOptions::new(Quantity::Temperature, View::FaceOn);
        opts.scale = Scale::Linear;
        let range = ColorRange::new(0.0, 49.0, Scale::Linear).unwrap();
        let ((w, h), _) = picture_size(&frame);
        let k = upscale(frame.nx, frame.ny);
        let (left, top) = (
            (MARGIN + Y_LABEL_AREA) as usize,
            (TITLE_H + MARGIN) as usize,
        );
        let plot = frame.ny * k;
        let by_row: Vec<f64> = (0..frame.len()).map(|p| (p / frame.nx) as f64).collect();
        let by_col: Vec<f64> = (0..frame.len()).map(|p| (p % frame.nx) as f64).collect();
        for (field, high, low) in [
            (
                &by_row,
                (left + plot / 2, top + 2),
                (left + plot / 2, top + plot - 3),
            ),
            (
                &by_col,
                (left + plot - 3, top + plot / 2),
                (left + 2, top + plot / 2),
            ),
        ] {
            let mut buf = vec![0u8; 3 * (w * h) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                draw_on(&root, &snap, field, &frame, &opts, range).unwrap();
                root.present().unwrap();
            }
            let at = |(x, y): (usize, usize)| {
                let p = 3 * (y * w as usize + x);
                [buf[p], buf[p + 1], buf[p + 2]]
            };
            assert_eq!(at(high), opts.colormap.rgb(1.0));
            assert_eq!(at(low), opts.colormap.rgb(0.0));
        }
    }

    /// A disk about the accretor of a q = 0.1 binary in a box from (−1.5, −1, −0.5) to
    /// (0.5, 1, 0.5), written as sphdisk writes it (positions shifted into [0, BoxSize],
    /// `[binary] q` in `/Parameters`) and read back into the run's frame.
    fn binary_snapshot(dir: &Path) -> (PathBuf, Snapshot) {
        use crate::io::hdf5::{RunMetadata, Units, read_snapshot, write_snapshot};
        let mut s = cloud(3);
        let lo = [-1.5, -1.0, -0.5];
        let hi = [0.5, 1.0, 0.5];
        for a in 0..3 {
            s.pos[a].iter_mut().for_each(|x| *x *= 0.4);
            s.pos[a].iter_mut().for_each(|x| *x -= lo[a]);
            s.point_masses[0].pos[a] -= lo[a];
            s.shift[a] = -lo[a];
            s.box_lo[a] = 0.0;
            s.box_hi[a] = hi[a] - lo[a];
        }
        let meta = RunMetadata {
            parameters: [("binary.q", "0.1"), ("problem.kind", "\"cv\"")]
                .into_iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            units: Units::default(),
            periodic: false,
            physical: false,
        };
        let path = dir.join("snap_0000.hdf5");
        write_snapshot(&path, &s, &meta, 1).unwrap();
        let snap = read_snapshot(&path).unwrap().in_run_frame();
        (path, snap)
    }

    #[test]
    fn roche_lobes_are_drawn_over_binary_snapshots() {
        use crate::render::overlay::{OVERLAY_RGB, mass_ratio_of, roche_curves};
        let dir = tempfile::tempdir().unwrap();
        let (path, snap) = binary_snapshot(dir.path());
        assert_eq!(snap.box_lo, [-1.5, -1.0, -0.5]);
        let q = mass_ratio_of(&path).unwrap();
        assert_eq!(q, Some(0.1));
        for view in [View::FaceOn, View::EdgeOn, View::Slice] {
            let quantity = match view {
                View::Slice => Quantity::Density,
                _ => Quantity::ColumnDensity,
            };
            let mut opts = RenderOptions::new(quantity, view);
            opts.resolution = (120, 120);
            opts.roche_q = q;
            let frame = frame_for(&snap, &opts).unwrap();
            let (field, _, _) = render_field(&snap, &opts).unwrap();
            let range = ColorRange::new(1e-3, 10.0, Scale::Log).unwrap();
            let ((w, h), _) = picture_size(&frame);
            let k = upscale(frame.nx, frame.ny) as i32;
            let (left, top) = ((MARGIN + Y_LABEL_AREA) as i32, (TITLE_H + MARGIN) as i32);
            let map = PixelMap {
                frame,
                px: left..left + frame.nx as i32 * k,
                py: top..top + frame.ny as i32 * k,
            };
            let draw = |o: &RenderOptions| {
                let mut buf = vec![0u8; 3 * (w * h) as usize];
                {
                    let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                    draw_on(&root, &snap, &field, &frame, o, range).unwrap();
                    root.present().unwrap();
                }
                buf
            };
            let at = |buf: &[u8], (x, y): (i32, i32)| {
                let p = 3 * (y as usize * w as usize + x as usize);
                [buf[p], buf[p + 1], buf[p + 2]]
            };
            let with = draw(&opts);
            let without = draw(&RenderOptions {
                roche_q: None,
                ..opts.clone()
            });
            // Every point of both outlines inside the image (and its pixel) is white, and
            // was not before; most of both lobes is in the picture.
            let (lobes, l1) = roche_curves(0.1, view, [0.0; 3]);
            for lobe in &lobes {
                let pixels: Vec<_> = lobe.iter().filter_map(|&p| map.pixel(p)).collect();
                assert!(pixels.len() > lobe.len() / 2, "{view}: {}", pixels.len());
                for &p in &pixels {
                    assert_eq!(at(&with, p), OVERLAY_RGB, "{view} at {p:?}");
                }
                assert!(pixels.iter().any(|&p| at(&without, p) != OVERLAY_RGB));
            }
            // The cross at L1.
            let (c, r) = map.pixel(l1).unwrap();
            for p in [(c - 4, r), (c + 4, r), (c, r - 4), (c, r + 4)] {
                assert_eq!(at(&with, p), OVERLAY_RGB, "{view}: cross at {p:?}");
            }
            // Off the lines the picture is unchanged: the centre of the accretor's lobe
            // away from the star's ring, and the corner of the box.
            for p in [
                map.pixel([0.3, 0.02]).unwrap(),
                (map.px.start + 2, map.py.end - 3),
            ] {
                assert_eq!(at(&with, p), at(&without, p), "{view} at {p:?}");
            }
        }
        // And into a PNG, whose bytes differ from the picture without the lobes.
        let mut opts = RenderOptions::new(Quantity::ColumnDensity, View::FaceOn);
        opts.resolution = (64, 64);
        render_png(&snap, &opts, &dir.path().join("plain.png")).unwrap();
        opts.roche_q = q;
        render_png(&snap, &opts, &dir.path().join("roche.png")).unwrap();
        let read = |n: &str| std::fs::read(dir.path().join(n)).unwrap();
        assert_ne!(read("plain.png"), read("roche.png"));
    }

    #[test]
    fn common_range_spans_all_fields() {
        let a = [0.0, 2.0, -1.0];
        let b = [5.0, f64::NAN, 0.5];
        assert_eq!(common_range(&[&a, &b], Scale::Linear), (-1.0, 5.0));
        // Log: from the 1% quantile of the positive values, at most four decades.
        assert_eq!(common_range(&[&a, &b], Scale::Log), (0.5, 5.0));
        let wide: Vec<f64> = (0..1000)
            .map(|k| 10f64.powf(-8.0 + 8.0 * k as f64 / 999.0))
            .collect();
        assert_eq!(common_range(&[&wide], Scale::Log), (1e-4, 1.0));
        // A blast's shell over its background: the range spans the data, not 10⁴.
        let shell: Vec<f64> = (0..1000)
            .map(|k| 1.0 + 2.0 * (k % 7) as f64 / 6.0)
            .collect();
        assert_eq!(common_range(&[&shell], Scale::Log), (1.0, 3.0));
        assert_eq!(common_range(&[&[0.0, -2.0]], Scale::Log), (1e-4, 1.0));
        assert_eq!(common_range(&[&[3.0, 3.0]], Scale::Linear), (1.5, 4.5));
        assert_eq!(common_range(&[], Scale::Linear), (0.0, 1.0));
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(&0.0), "0");
        assert_eq!(tick(&0.25), "0.25");
        assert_eq!(tick(&-3.0), "-3");
        assert_eq!(tick(&1.5e-5), "1.5e-5");
        assert_eq!(tick(&2.0e6), "2e6");
        assert_eq!(ticks_for(0.6)(&-2.78e-17), "0");
        assert_eq!(ticks_for(0.6)(&0.1), "0.1");
    }

    #[test]
    fn physical_units_are_read_for_axes_and_colour_bar() {
        use crate::io::hdf5::{RunMetadata, read_periodic, read_units, write_snapshot};
        let dir = tempfile::tempdir().unwrap();
        let snap = cloud(3);
        let units = Units {
            mass_cgs: 2e33,
            length_cgs: 1.5e13,
            time_cgs: 3.15e7,
            mean_molecular_weight: 2.3,
        };
        let meta = RunMetadata {
            parameters: [("units.mean_molecular_weight".to_string(), "2.3".to_string())].into(),
            units,
            periodic: true,
            physical: true,
        };
        let path = dir.path().join("physical.hdf5");
        write_snapshot(&path, &snap, &meta, 1).unwrap();
        assert_eq!(read_units(&path).unwrap(), Some(units));
        assert!(read_periodic(&path).unwrap());
        // G = 1 code units: none, and the pictures say "code units".
        let plain = dir.path().join("plain.hdf5");
        write_snapshot(&plain, &snap, &RunMetadata::default(), 1).unwrap();
        assert_eq!(read_units(&plain).unwrap(), None);
        assert!(!read_periodic(&plain).unwrap());
        let (k, name) = Quantity::Temperature.cgs(3, &units);
        assert_eq!(
            (k, name.as_str()),
            (units.kelvin_per_specific_energy(), "K")
        );
        let (k, name) = Quantity::ColumnDensity.cgs(3, &units);
        assert_eq!((k, name.as_str()), (2e33 / (1.5e13 * 1.5e13), "g cm⁻²"));
        // Drawn: a picture with units differs from one without (labels in cm and K).
        let mut opts = RenderOptions::new(Quantity::Temperature, View::FaceOn);
        opts.resolution = (40, 40);
        let a = render_png(&snap, &opts, &dir.path().join("a.png")).unwrap();
        opts.units = Some(units);
        let b = render_png(&snap, &opts, &dir.path().join("b.png")).unwrap();
        assert_eq!(a.field, b.field);
        assert_ne!(
            std::fs::read(dir.path().join("a.png")).unwrap(),
            std::fs::read(dir.path().join("b.png")).unwrap()
        );
    }
}
