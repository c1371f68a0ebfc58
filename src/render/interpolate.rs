//! SPH kernel interpolation of a snapshot onto a pixel grid: the column density (the 3D kernel
//! integrated along the line of sight), column-weighted projections of other quantities,
//! slices through 3D data, and the plane of 2D data.
//!
//! Every particle is spread with the kernel its run used (the snapshot's `kernel`, from
//! SWIFT's `/HydroScheme`), and its footprint on the grid is normalised to the exact
//! integral of that kernel over the image plane, and a particle smaller than a pixel is deposited cloud-in-cell, so
//! an image holds the mass of the particles inside it however coarse its pixels are.

use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;
use std::sync::OnceLock;

use anyhow::{Context, Result, bail, ensure};
use rayon::prelude::*;

use crate::io::snapshot::Snapshot;
use crate::kernel::{Kernel, KernelKind};
use crate::render::colormap::{Colormap, Scale};

/// What an image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Σ = ∫ ρ dz along the line of sight (3D); the surface density itself (2D).
    ColumnDensity,
    /// ρ (in 2D runs the surface density Σ).
    Density,
    /// Specific viscous dissipation rate `diss`.
    Dissipation,
    /// P/ρ = k_B T/(μ m_p), the temperature in velocity² (c_s² of the isothermal sound
    /// speed): for every equation of state, the locally isothermal one included.
    Temperature,
    /// Speed |v|.
    Velocity,
}

impl Quantity {
    pub const ALL: [Quantity; 5] = [
        Quantity::ColumnDensity,
        Quantity::Density,
        Quantity::Dissipation,
        Quantity::Temperature,
        Quantity::Velocity,
    ];

    /// The name on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::ColumnDensity => "column-density",
            Quantity::Density => "density",
            Quantity::Dissipation => "dissipation",
            Quantity::Temperature => "temperature",
            Quantity::Velocity => "velocity",
        }
    }

    /// The axis label of the colour bar.
    pub fn label(&self) -> &'static str {
        match self {
            Quantity::ColumnDensity => "Σ (column density)",
            Quantity::Density => "ρ (density)",
            Quantity::Dissipation => "specific dissipation rate",
            Quantity::Temperature => "P/ρ = kT/μm_p (temperature)",
            Quantity::Velocity => "|v| (speed)",
        }
    }

    /// Units of the quantity, in code units, for a run of `dimension` (2D: ρ is Σ).
    pub fn unit(&self, dimension: usize) -> &'static str {
        match self {
            Quantity::ColumnDensity => "mass / length²",
            Quantity::Density if dimension == 2 => "mass / length²",
            Quantity::Density => "mass / length³",
            Quantity::Dissipation => "energy / mass / time",
            Quantity::Temperature => "energy / mass",
            Quantity::Velocity => "length / time",
        }
    }

    /// The factor to cgs of the quantity in code units `u`, and the cgs unit's name:
    /// the temperature P/ρ in K (T = μ m_p P/(ρ k_B)), the rest in g, cm, s.
    pub fn cgs(&self, dimension: usize, u: &crate::io::hdf5::Units) -> (f64, String) {
        let (m, l, t) = (u.mass_cgs, u.length_cgs, u.time_cgs);
        let (factor, name) = match self {
            Quantity::ColumnDensity => (m / (l * l), "g cm⁻²"),
            Quantity::Density if dimension == 2 => (m / (l * l), "g cm⁻²"),
            Quantity::Density => (m / (l * l * l), "g cm⁻³"),
            Quantity::Dissipation => (l * l / (t * t * t), "erg g⁻¹ s⁻¹"),
            Quantity::Temperature => (u.kelvin_per_specific_energy(), "K"),
            Quantity::Velocity => (l / t, "cm s⁻¹"),
        };
        (factor, name.to_string())
    }

    /// Densities span decades: log scale; the rest linear.
    pub fn default_scale(self) -> Scale {
        match self {
            Quantity::ColumnDensity | Quantity::Density => Scale::Log,
            _ => Scale::Linear,
        }
    }

    pub fn default_colormap(self) -> Colormap {
        match self {
            Quantity::ColumnDensity | Quantity::Density => Colormap::Magma,
            _ => Colormap::Viridis,
        }
    }
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Quantity {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "column-density" | "column" | "sigma" => Quantity::ColumnDensity,
            "density" | "rho" => Quantity::Density,
            "dissipation" | "diss" => Quantity::Dissipation,
            "temperature" | "T" => Quantity::Temperature,
            "velocity" | "speed" | "v" => Quantity::Velocity,
            _ => bail!(
                "unknown quantity {s:?}: expected column-density, density, dissipation, \
                 temperature or velocity"
            ),
        })
    }
}

/// Where the image plane lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Projected along z onto the x–y plane (2D runs: the plane itself).
    FaceOn,
    /// Projected along y onto the x–z plane (3D only).
    EdgeOn,
    /// The plane z = z_slice in x–y (default: the middle of the box; 2D runs: the plane).
    Slice,
}

impl View {
    pub const ALL: [View; 3] = [View::FaceOn, View::EdgeOn, View::Slice];

    pub fn name(self) -> &'static str {
        match self {
            View::FaceOn => "face-on",
            View::EdgeOn => "edge-on",
            View::Slice => "slice",
        }
    }

    /// Names of the horizontal and vertical image axes.
    pub fn axes(self) -> (&'static str, &'static str) {
        match self {
            View::FaceOn | View::Slice => ("x", "y"),
            View::EdgeOn => ("x", "z"),
        }
    }

    /// Snapshot coordinate indices of the horizontal and vertical image axes.
    fn axis_indices(self) -> (usize, usize) {
        match self {
            View::FaceOn | View::Slice => (0, 1),
            View::EdgeOn => (0, 2),
        }
    }
}

impl fmt::Display for View {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for View {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "face-on" | "faceon" | "xy" => View::FaceOn,
            "edge-on" | "edgeon" | "xz" => View::EdgeOn,
            "slice" => View::Slice,
            _ => bail!("unknown view {s:?}: expected face-on, edge-on or slice"),
        })
    }
}

/// The rectangle an image covers, in code units along the view's two axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    pub x: (f64, f64),
    pub y: (f64, f64),
}

impl Extent {
    /// A checked extent: finite, with `x.0 < x.1` and `y.0 < y.1`.
    pub fn new(x: (f64, f64), y: (f64, f64)) -> Result<Self> {
        let e = Self { x, y };
        e.check()?;
        Ok(e)
    }

    fn check(&self) -> Result<()> {
        for (name, (a, b)) in [("x", self.x), ("y", self.y)] {
            ensure!(
                a.is_finite() && b.is_finite() && a < b,
                "image extent along {name} must be finite with lo < hi, got {a} .. {b}"
            );
        }
        Ok(())
    }

    pub fn width(&self) -> f64 {
        self.x.1 - self.x.0
    }

    pub fn height(&self) -> f64 {
        self.y.1 - self.y.0
    }

    /// The default extent of `view`: the particles' bounds along the view's axes widened
    /// by one kernel support, within the box (a disk that fills a fifth of its box fills
    /// the picture; particles that fill a periodic box give the box). Where the box is not
    /// usable, the widened bounds alone.
    pub fn default_for(snap: &Snapshot, view: View) -> Result<Self> {
        let (a, b) = view.axis_indices();
        let pad = snap.kernel.support_factor() * snap.h.iter().copied().fold(0.0, f64::max);
        let bounds = |d: usize| {
            let (lo, hi) = snap.pos[d]
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
            (lo - pad, hi + pad)
        };
        let fitted = Self {
            x: bounds(a),
            y: bounds(b),
        };
        let from_box = Self {
            x: (snap.box_lo[a], snap.box_hi[a]),
            y: (snap.box_lo[b], snap.box_hi[b]),
        };
        if from_box.check().is_ok() {
            let within = Self {
                x: (fitted.x.0.max(from_box.x.0), fitted.x.1.min(from_box.x.1)),
                y: (fitted.y.0.max(from_box.y.0), fitted.y.1.min(from_box.y.1)),
            };
            return Ok(if within.check().is_ok() {
                within
            } else {
                from_box
            });
        }
        Self::new(fitted.x, fitted.y)
            .context("neither the snapshot's box nor its particles give an image extent")
    }

    /// The box along the view's axes, or where it is not usable, [`Self::default_for`].
    pub fn of_box(snap: &Snapshot, view: View) -> Result<Self> {
        let (a, b) = view.axis_indices();
        let from_box = Self {
            x: (snap.box_lo[a], snap.box_hi[a]),
            y: (snap.box_lo[b], snap.box_hi[b]),
        };
        if from_box.check().is_ok() {
            Ok(from_box)
        } else {
            Self::default_for(snap, view)
        }
    }

    /// The smallest extent holding both.
    pub fn union(&self, other: &Self) -> Self {
        Self {
            x: (self.x.0.min(other.x.0), self.x.1.max(other.x.1)),
            y: (self.y.0.min(other.y.0), self.y.1.max(other.y.1)),
        }
    }
}

/// `snap` with the periodic images of its particles that lie within one kernel support of
/// the box's faces across the view's two axes (and the corners), so that a periodic box's
/// picture has no dark bands at its borders: a particle near x = lo reappears at x + L,
/// where its kernel reaches into the picture from the other side. A 3D slice also takes
/// the images across the line of sight (a slice near z = lo cuts the kernels of particles
/// near z = hi); a projection does not (the column would count them twice).
pub fn with_periodic_images(snap: &Snapshot, view: View) -> Snapshot {
    let (a, b) = view.axis_indices();
    let c = (view == View::Slice && snap.dimension == 3).then_some(3 - a - b);
    let mut out = snap.clone();
    let shifts = |d: usize, x: f64, reach: f64| -> Vec<f64> {
        let (lo, hi) = (snap.box_lo[d], snap.box_hi[d]);
        let len = hi - lo;
        let mut s = vec![0.0];
        if !(len > 0.0) || d >= snap.dimension {
            return s;
        }
        if x - lo < reach {
            s.push(len);
        }
        if hi - x < reach {
            s.push(-len);
        }
        s
    };
    for i in 0..snap.len() {
        let reach = snap.kernel.support_factor() * snap.h[i];
        let across = c.map_or(vec![0.0], |c| shifts(c, snap.pos[c][i], reach));
        for &sa in &shifts(a, snap.pos[a][i], reach) {
            for &sb in &shifts(b, snap.pos[b][i], reach) {
                for &sc in &across {
                    if sa == 0.0 && sb == 0.0 && sc == 0.0 {
                        continue;
                    }
                    for d in 0..3 {
                        let shift = if d == a {
                            sa
                        } else if d == b {
                            sb
                        } else if Some(d) == c {
                            sc
                        } else {
                            0.0
                        };
                        out.pos[d].push(snap.pos[d][i] + shift);
                        out.vel[d].push(snap.vel[d][i]);
                    }
                    out.id.push(snap.id[i]);
                    out.mass.push(snap.mass[i]);
                    out.h.push(snap.h[i]);
                    out.rho.push(snap.rho[i]);
                    out.u.push(snap.u[i]);
                    out.p.push(snap.p[i]);
                    out.diss.push(snap.diss[i]);
                }
            }
        }
    }
    out
}

/// A pixel grid: `nx` × `ny` pixels covering `x` × `y`. Values are taken at pixel centres
/// `(x.0 + (i + ½) dx, y.0 + (j + ½) dy)`; fields are row-major, row `j = 0` at the bottom
/// (`y.0`), so pixel (i, j) is `field[j * nx + i]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub x: (f64, f64),
    pub y: (f64, f64),
    pub nx: usize,
    pub ny: usize,
}

/// The largest image we agree to compute (2^28 pixels, 2 GiB of f64).
const MAX_PIXELS: usize = 1 << 28;

impl Frame {
    pub fn new(extent: Extent, nx: usize, ny: usize) -> Self {
        Self {
            x: extent.x,
            y: extent.y,
            nx,
            ny,
        }
    }

    /// The grid of (nearly) square pixels that covers `extent` and fits in `max` pixels:
    /// the longer side relative to `max` gets all its pixels, the other as many as fit.
    pub fn fit(extent: Extent, max: (usize, usize)) -> Self {
        let (mx, my) = (max.0.max(1), max.1.max(1));
        let d = (extent.width() / mx as f64).max(extent.height() / my as f64);
        let n = |len: f64, m: usize| ((len / d).round() as usize).clamp(1, m);
        Self::new(extent, n(extent.width(), mx), n(extent.height(), my))
    }

    pub fn extent(&self) -> Extent {
        Extent {
            x: self.x,
            y: self.y,
        }
    }

    pub fn dx(&self) -> f64 {
        (self.x.1 - self.x.0) / self.nx as f64
    }

    pub fn dy(&self) -> f64 {
        (self.y.1 - self.y.0) / self.ny as f64
    }

    pub fn pixel_area(&self) -> f64 {
        self.dx() * self.dy()
    }

    /// Centre of pixel (i, j).
    pub fn centre(&self, i: usize, j: usize) -> (f64, f64) {
        (
            self.x.0 + (i as f64 + 0.5) * self.dx(),
            self.y.0 + (j as f64 + 0.5) * self.dy(),
        )
    }

    pub fn len(&self) -> usize {
        self.nx * self.ny
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn check(&self) -> Result<()> {
        self.extent().check()?;
        ensure!(
            self.nx >= 1 && self.ny >= 1,
            "an image needs at least one pixel, got {} × {}",
            self.nx,
            self.ny
        );
        ensure!(
            self.nx
                .checked_mul(self.ny)
                .is_some_and(|n| n <= MAX_PIXELS),
            "image of {} × {} pixels is larger than the limit of {MAX_PIXELS} pixels",
            self.nx,
            self.ny
        );
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// The column kernel.

/// Intervals of the column-kernel table on q = R/h ∈ [0, support].
const TABLE_INTERVALS: usize = 1000;

/// Simpson intervals for each piece of a radial integral.
const SIMPSON_INTERVALS: usize = 200;

/// Radii (units of h) below the support where a kernel's polynomial pieces join: the
/// quadratures split there, so that each piece is smooth.
fn joins(kind: KernelKind) -> &'static [f64] {
    match kind {
        KernelKind::Cubic => &[1.0],
        KernelKind::Quintic => &[1.0, 2.0],
        _ => &[],
    }
}

/// The 3D kernel of `kind` integrated along the line of sight, tabulated in q = R/h at
/// `TABLE_INTERVALS + 1` points on [0, support]: F(R, h) = Y(R/h) / h², normalised so that
/// ∫ F d²R = 1 exactly for the table's linear interpolant.
fn column_table(kind: KernelKind) -> &'static [f64] {
    static TABLES: [OnceLock<Vec<f64>>; KernelKind::ALL.len()] =
        [const { OnceLock::new() }; KernelKind::ALL.len()];
    TABLES[kind as usize].get_or_init(|| {
        let (mut y, integral) = integrate_column_kernel(kind);
        for v in &mut y {
            *v /= integral;
        }
        y
    })
}

fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let n = SIMPSON_INTERVALS;
    let d = (b - a) / n as f64;
    let mut sum = f(a) + f(b);
    for k in 1..n {
        sum += f(a + k as f64 * d) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * d / 3.0
}

/// ∫ f over [a, b] by Simpson's rule on each piece between the `cuts` inside (a, b).
fn simpson_pieces(f: impl Fn(f64) -> f64, a: f64, b: f64, cuts: impl Iterator<Item = f64>) -> f64 {
    let mut sum = 0.0;
    let mut lo = a;
    for c in cuts.filter(|&c| c > a && c < b) {
        sum += simpson(&f, lo, c);
        lo = c;
    }
    sum + simpson(&f, lo, b)
}

/// Y(q) by quadrature along the line of sight, and ∫ F d²R of its linear interpolant (1 to
/// the quadrature's accuracy).
fn integrate_column_kernel(kind: KernelKind) -> (Vec<f64>, f64) {
    let unit = Kernel::<3>::of_kind(kind, 1.0);
    let support = kind.support_factor();
    let dq = support / TABLE_INTERVALS as f64;
    let smax_sq = support * support;
    let mut y = vec![0.0; TABLE_INTERVALS + 1];
    // y[TABLE_INTERVALS] (q = support) stays 0: the line of sight only grazes the support.
    for (i, yi) in y.iter_mut().enumerate().take(TABLE_INTERVALS) {
        let q = i as f64 * dq;
        let f = |s: f64| unit.w((q * q + s * s).sqrt());
        let smax = (smax_sq - q * q).max(0.0).sqrt();
        // Split where the line of sight crosses the kernel's joins.
        let cuts = joins(kind)
            .iter()
            .filter(|&&r| r > q)
            .map(|&r| (r * r - q * q).sqrt());
        *yi = 2.0 * simpson_pieces(f, 0.0, smax, cuts);
    }
    // ∫ F d²R = 2π ∫ Y(q) q dq, exactly for the piecewise-linear interpolant of the table.
    let mut integral = 0.0;
    for i in 0..TABLE_INTERVALS {
        let a = i as f64 * dq;
        let (ya, yb) = (y[i], y[i + 1]);
        integral += ya * (a * dq + 0.5 * dq * dq) + (yb - ya) * (0.5 * a * dq + dq * dq / 3.0);
    }
    (y, 2.0 * PI * integral)
}

/// Y(q), the dimensionless column kernel (linear interpolation in the table of a kernel
/// with support `support`).
#[inline]
fn column_shape(table: &[f64], support: f64, q: f64) -> f64 {
    if !(q < support) {
        return 0.0;
    }
    let x = q * (TABLE_INTERVALS as f64 / support);
    let i = (x as usize).min(TABLE_INTERVALS - 1);
    let f = x - i as f64;
    table[i] + (table[i + 1] - table[i]) * f
}

/// F(R, h): the 3D kernel of `kind` integrated along a line of sight at projected distance
/// R, a 2D kernel with ∫ F d²R = 1 and support R < support · h.
pub fn column_kernel(kind: KernelKind, r: f64, h: f64) -> f64 {
    column_shape(column_table(kind), kind.support_factor(), r / h) / (h * h)
}

/// G(ζ) = ∫ W₃(√(R² + z²), 1) d²R = 2π ∫_ζ^support W₃(r) r dr at height ζ = z/h: the part
/// of a 3D kernel that a plane at distance z from the particle cuts, times h. ∫ G dζ = 1.
fn slice_integral(kind: KernelKind, zeta: f64) -> f64 {
    let z = zeta.abs();
    let support = kind.support_factor();
    if !(z < support) {
        return 0.0;
    }
    let unit = Kernel::<3>::of_kind(kind, 1.0);
    2.0 * PI * simpson_pieces(|r| unit.w(r) * r, z, support, joins(kind).iter().copied())
}

// ---------------------------------------------------------------------------------------
// Interpolation.

/// The kernel a particle spreads over the image plane.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Footprint {
    /// The 3D kernel integrated along the line of sight (3D face-on and edge-on).
    Column,
    /// The 2D kernel in the plane of a 2D run.
    Plane,
    /// The 3D kernel cut by the plane z = z0 of a 3D run.
    Slice { z0: f64 },
}

/// Footprints spanning more pixels than this across are normalised analytically: their
/// pixel sums match the kernel's integral to far better than 1e-4 already.
const EXACT_NORM_MAX_SPAN: f64 = 64.0;

/// One particle, ready to deposit: image-plane position, smoothing length, in-plane support
/// radius, and the weights per unit dimensionless kernel value of the numerator and (for
/// column-weighted averages) the denominator.
#[derive(Clone, Copy, Debug)]
struct Splat {
    x: f64,
    y: f64,
    inv_h2: f64,
    /// (Δz/h)² between particle and slice plane; 0 for projections and 2D.
    zeta2: f64,
    radius: f64,
    num: f64,
    den: f64,
    /// Smaller than a pixel: bilinear (cloud-in-cell) deposit at its position.
    cic: bool,
    /// Pixel rows the splat touches, clipped to the frame.
    rows: (usize, usize),
}

/// Dimensionless kernel shapes with h = 1; their prefactors cancel in the normalisation.
#[derive(Clone, Copy)]
struct Shapes<'a> {
    footprint: Footprint,
    kind: KernelKind,
    /// The kernel's support radius in units of h.
    support: f64,
    table: &'a [f64],
    k2: Kernel<2>,
    k3: Kernel<3>,
}

impl Shapes<'_> {
    /// Kernel value at squared in-plane distance `q2` (units of h²).
    #[inline]
    fn value(&self, q2: f64, zeta2: f64) -> f64 {
        match self.footprint {
            Footprint::Column => column_shape(self.table, self.support, q2.sqrt()),
            Footprint::Plane => self.k2.w(q2.sqrt()),
            Footprint::Slice { .. } => self.k3.w((q2 + zeta2).sqrt()),
        }
    }

    /// ∫ value d²q over the plane.
    fn integral(&self, zeta2: f64) -> f64 {
        match self.footprint {
            Footprint::Column | Footprint::Plane => 1.0,
            Footprint::Slice { .. } => slice_integral(self.kind, zeta2.sqrt()),
        }
    }
}

/// Pixel indices (possibly outside the frame) whose centres lie within [c − r, c + r] on an
/// axis starting at `o` with spacing `d`; empty when `lo > hi`.
#[inline]
fn centre_range(c: f64, r: f64, o: f64, d: f64) -> (i64, i64) {
    (
        ((c - r - o) / d - 0.5).ceil() as i64,
        ((c + r - o) / d - 0.5).floor() as i64,
    )
}

/// Σ of the kernel over every pixel centre of the (unbounded) grid within the footprint.
fn footprint_sum(s: &Splat, frame: &Frame, shapes: &Shapes) -> f64 {
    let (dx, dy) = (frame.dx(), frame.dy());
    let (j0, j1) = centre_range(s.y, s.radius, frame.y.0, dy);
    let r2 = s.radius * s.radius;
    let mut sum = 0.0;
    for j in j0..=j1 {
        let ddy = frame.y.0 + (j as f64 + 0.5) * dy - s.y;
        let rem = r2 - ddy * ddy;
        if rem < 0.0 {
            continue;
        }
        let (i0, i1) = centre_range(s.x, rem.sqrt(), frame.x.0, dx);
        for i in i0..=i1 {
            let ddx = frame.x.0 + (i as f64 + 0.5) * dx - s.x;
            sum += shapes.value((ddx * ddx + ddy * ddy) * s.inv_h2, s.zeta2);
        }
    }
    sum
}

/// Lower pixel index and weight of the upper neighbour for a bilinear deposit at `c`.
#[inline]
fn cic_axis(c: f64, o: f64, d: f64) -> (i64, f64) {
    let f = (c - o) / d - 0.5;
    let i = f.floor();
    (i as i64, f - i)
}

/// Interpolates `quantity` from `snap` onto `frame` as seen from `view`; returns the field,
/// row-major from the bottom row (see [`Frame`]).
///
/// * 3D face-on/edge-on: column density Σ = Σ_j m_j F(|R − R_j|, h_j); any other quantity A
///   is the column-weighted mean Σ_j m_j A_j F_j / Σ_j m_j F_j (∫ A ρ dz / ∫ ρ dz).
/// * 3D slice at z = `slice_z` (default: the middle of the box):
///   A = Σ_j (m_j / ρ_j) A_j W₃(|x − x_j|, h_j); density is Σ_j m_j W₃.
/// * 2D (face-on or slice, the plane itself; `slice_z` unused):
///   A = Σ_j (m_j / ρ_j) A_j W₂; column density and density are both Σ = Σ_j m_j W₂.
///
/// Pixels no particle reaches are 0.
pub fn interpolate(
    snap: &Snapshot,
    quantity: Quantity,
    view: View,
    frame: &Frame,
    slice_z: Option<f64>,
) -> Result<Vec<f64>> {
    interpolate_counted(snap, quantity, view, frame, slice_z).map(|(field, _)| field)
}

/// [`interpolate`], with the number of particles that reach the frame (0: a blank field).
pub fn interpolate_counted(
    snap: &Snapshot,
    quantity: Quantity,
    view: View,
    frame: &Frame,
    slice_z: Option<f64>,
) -> Result<(Vec<f64>, usize)> {
    frame.check()?;
    check_lengths(snap)?;
    let footprint = match (snap.dimension, view) {
        (1, _) => bail!("render needs a 2D or 3D snapshot; 1D runs are plotted as profiles"),
        (2, View::EdgeOn) => {
            bail!("a 2D snapshot has no edge-on view: the face-on view shows its plane")
        }
        (2, _) => Footprint::Plane,
        (3, View::Slice) => {
            if quantity == Quantity::ColumnDensity {
                bail!(
                    "column density is a projection: use the face-on or edge-on view, or \
                     density for a slice"
                );
            }
            let z0 = slice_z.unwrap_or(0.5 * (snap.box_lo[2] + snap.box_hi[2]));
            ensure!(z0.is_finite(), "slice height must be finite, got {z0}");
            Footprint::Slice { z0 }
        }
        (3, _) => Footprint::Column,
        (d, _) => bail!("snapshot dimension must be 1, 2 or 3, got {d}"),
    };
    let averaged = footprint == Footprint::Column && quantity != Quantity::ColumnDensity;
    let kind = snap.kernel;
    let support = kind.support_factor();
    let shapes = Shapes {
        footprint,
        kind,
        support,
        table: column_table(kind),
        k2: Kernel::<2>::of_kind(kind, 1.0),
        k3: Kernel::<3>::of_kind(kind, 1.0),
    };
    let (ax, ay) = view.axis_indices();
    let (dx, dy) = (frame.dx(), frame.dy());
    let area = frame.pixel_area();
    let cic_below = dx.max(dy);
    let exact_below = 0.5 * EXACT_NORM_MAX_SPAN * dx.min(dy);

    let n = snap.len();
    ensure!(n <= u32::MAX as usize, "too many particles to render ({n})");
    let splats: Vec<Option<Splat>> = (0..n)
        .into_par_iter()
        .map(|j| -> Result<Option<Splat>> {
            let name = || match snap.id.get(j) {
                Some(id) => format!("particle {id}"),
                None => format!("particle #{j}"),
            };
            let (m, h) = (snap.mass[j], snap.h[j]);
            let (x, y) = (snap.pos[ax][j], snap.pos[ay][j]);
            ensure!(
                m.is_finite() && x.is_finite() && y.is_finite(),
                "{}: non-finite mass or position",
                name()
            );
            ensure!(
                h > 0.0 && h.is_finite(),
                "{}: smoothing length must be > 0, got {h}",
                name()
            );
            let zeta2 = match footprint {
                Footprint::Slice { z0 } => {
                    let zeta = (snap.pos[2][j] - z0) / h;
                    if !(zeta.abs() < support) {
                        return Ok(None);
                    }
                    zeta * zeta
                }
                _ => 0.0,
            };
            let value = || match quantity {
                Quantity::ColumnDensity | Quantity::Density => snap.rho[j],
                Quantity::Dissipation => snap.diss[j],
                Quantity::Temperature if snap.rho[j] > 0.0 => snap.p[j] / snap.rho[j],
                Quantity::Temperature => 0.0,
                Quantity::Velocity => {
                    let v = [snap.vel[0][j], snap.vel[1][j], snap.vel[2][j]];
                    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
                }
            };
            // Weights of the numerator and denominator per unit of the physical kernel.
            let (wn, wd) = if footprint == Footprint::Column {
                if averaged { (m * value(), m) } else { (m, 0.0) }
            } else if matches!(quantity, Quantity::ColumnDensity | Quantity::Density) {
                (m, 0.0)
            } else {
                let rho = snap.rho[j];
                ensure!(
                    rho > 0.0 && rho.is_finite(),
                    "{}: density must be > 0 to interpolate {quantity}, got {rho}",
                    name()
                );
                (m / rho * value(), 0.0)
            };
            ensure!(
                wn.is_finite(),
                "{}: non-finite {quantity} ({})",
                name(),
                value()
            );
            // Exact integral of the physical kernel over the plane: 1, or G(ζ)/h in a slice.
            let total = match footprint {
                Footprint::Slice { .. } => slice_integral(kind, zeta2.sqrt()) / h,
                _ => 1.0,
            };
            let radius = h * (support * support - zeta2).max(0.0).sqrt();
            let mut s = Splat {
                x,
                y,
                inv_h2: 1.0 / (h * h),
                zeta2,
                radius,
                num: 0.0,
                den: 0.0,
                cic: radius < cic_below,
                rows: (0, 0),
            };
            let (j0, j1) = if s.cic {
                let (j0, _) = cic_axis(y, frame.y.0, dy);
                let (i0, _) = cic_axis(x, frame.x.0, dx);
                if i0 + 1 < 0 || i0 >= frame.nx as i64 {
                    return Ok(None);
                }
                (j0, j0 + 1)
            } else {
                let (i0, i1) = centre_range(x, radius, frame.x.0, dx);
                if i1 < 0 || i0 >= frame.nx as i64 {
                    return Ok(None);
                }
                centre_range(y, radius, frame.y.0, dy)
            };
            if j1 < 0 || j0 >= frame.ny as i64 || j0 > j1 {
                return Ok(None);
            }
            s.rows = (j0.max(0) as usize, (j1 as usize).min(frame.ny - 1));
            // Per unit dimensionless kernel value: w · total / (pixel area · Σ kernel).
            let scale = if s.cic {
                total / area
            } else {
                let sum = if radius <= exact_below {
                    footprint_sum(&s, frame, &shapes)
                } else {
                    shapes.integral(zeta2) * h * h / area
                };
                if !(sum > 0.0) {
                    // Cannot happen with radius ≥ a pixel; deposit cloud-in-cell regardless.
                    s.cic = true;
                    total / area
                } else {
                    total / (area * sum)
                }
            };
            s.num = wn * scale;
            s.den = wd * scale;
            Ok(Some(s))
        })
        .collect::<Result<_>>()?;
    let splats: Vec<Splat> = splats.into_iter().flatten().collect();

    // Bands of rows, each filled by one task from the particles that touch it: no two tasks
    // write the same pixel, and each pixel sums its particles in snapshot order whatever the
    // number of threads.
    let threads = rayon::current_num_threads().max(1);
    let band_rows = frame.ny.div_ceil(8 * threads).max(1);
    let bands = frame.ny.div_ceil(band_rows);
    let mut start = vec![0usize; bands + 1];
    for s in &splats {
        for b in s.rows.0 / band_rows..=s.rows.1 / band_rows {
            start[b + 1] += 1;
        }
    }
    for b in 0..bands {
        start[b + 1] += start[b];
    }
    let mut members = vec![0u32; start[bands]];
    let mut fill = start.clone();
    for (k, s) in splats.iter().enumerate() {
        for b in s.rows.0 / band_rows..=s.rows.1 / band_rows {
            members[fill[b]] = k as u32;
            fill[b] += 1;
        }
    }

    let nx = frame.nx;
    let deposit = |b: usize, num: &mut [f64], mut den: Option<&mut [f64]>| {
        let row0 = b * band_rows;
        let row_end = row0 + num.len() / nx;
        for &k in &members[start[b]..start[b + 1]] {
            let s = &splats[k as usize];
            if s.cic {
                let (i0, tx) = cic_axis(s.x, frame.x.0, dx);
                let (j0, ty) = cic_axis(s.y, frame.y.0, dy);
                for (j, wy) in [(j0, 1.0 - ty), (j0 + 1, ty)] {
                    if j < row0 as i64 || j >= row_end as i64 {
                        continue;
                    }
                    let r = (j as usize - row0) * nx;
                    for (i, wx) in [(i0, 1.0 - tx), (i0 + 1, tx)] {
                        if i < 0 || i >= nx as i64 {
                            continue;
                        }
                        let p = r + i as usize;
                        num[p] += s.num * wx * wy;
                        if let Some(den) = den.as_deref_mut() {
                            den[p] += s.den * wx * wy;
                        }
                    }
                }
                continue;
            }
            let r2 = s.radius * s.radius;
            for j in s.rows.0.max(row0)..=s.rows.1.min(row_end - 1) {
                let ddy = frame.y.0 + (j as f64 + 0.5) * dy - s.y;
                let rem = r2 - ddy * ddy;
                if rem < 0.0 {
                    continue;
                }
                let (i0, i1) = centre_range(s.x, rem.sqrt(), frame.x.0, dx);
                if i1 < 0 || i0 >= nx as i64 {
                    continue;
                }
                let (i0, i1) = (i0.max(0) as usize, (i1 as usize).min(nx - 1));
                let r = (j - row0) * nx;
                let dy2 = ddy * ddy;
                for i in i0..=i1 {
                    let ddx = frame.x.0 + (i as f64 + 0.5) * dx - s.x;
                    let w = shapes.value((ddx * ddx + dy2) * s.inv_h2, s.zeta2);
                    num[r + i] += s.num * w;
                    if let Some(den) = den.as_deref_mut() {
                        den[r + i] += s.den * w;
                    }
                }
            }
        }
    };

    let mut field = vec![0.0; frame.len()];
    if averaged {
        let mut den = vec![0.0; frame.len()];
        field
            .par_chunks_mut(band_rows * nx)
            .zip(den.par_chunks_mut(band_rows * nx))
            .enumerate()
            .for_each(|(b, (num, den))| deposit(b, num, Some(den)));
        field.par_iter_mut().zip(&den).for_each(|(v, &d)| {
            *v = if d > 0.0 { *v / d } else { 0.0 };
        });
    } else {
        field
            .par_chunks_mut(band_rows * nx)
            .enumerate()
            .for_each(|(b, num)| deposit(b, num, None));
    }
    Ok((field, splats.len()))
}

/// The column density (3D: projected along the view; 2D: the surface density).
pub fn column_density(snap: &Snapshot, view: View, frame: &Frame) -> Result<Vec<f64>> {
    interpolate(snap, Quantity::ColumnDensity, view, frame, None)
}

fn check_lengths(snap: &Snapshot) -> Result<()> {
    let n = snap.len();
    let columns: [(&str, usize); 11] = [
        ("h", snap.h.len()),
        ("rho", snap.rho.len()),
        ("u", snap.u.len()),
        ("diss", snap.diss.len()),
        ("pos[0]", snap.pos[0].len()),
        ("pos[1]", snap.pos[1].len()),
        ("pos[2]", snap.pos[2].len()),
        ("vel[0]", snap.vel[0].len()),
        ("vel[1]", snap.vel[1].len()),
        ("vel[2]", snap.vel[2].len()),
        ("id", if snap.id.is_empty() { n } else { snap.id.len() }),
    ];
    for (name, len) in columns {
        ensure!(
            len == n,
            "snapshot column {name} has {len} entries for {n} particles"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A snapshot of `dimension` from positions, masses and smoothing lengths; ρ = 1, u and
    /// |v| given per particle.
    fn snapshot(
        dimension: usize,
        pos: &[[f64; 3]],
        mass: &[f64],
        h: &[f64],
        lo: [f64; 3],
        hi: [f64; 3],
    ) -> Snapshot {
        let n = pos.len();
        Snapshot {
            dimension,
            time: 0.25,
            box_lo: lo,
            box_hi: hi,
            id: (0..n as u64).collect(),
            pos: std::array::from_fn(|d| pos.iter().map(|p| p[d]).collect()),
            vel: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            mass: mass.to_vec(),
            h: h.to_vec(),
            rho: vec![1.0; n],
            u: vec![1.0; n],
            p: vec![1.0; n],
            diss: vec![0.0; n],
            ..Snapshot::default()
        }
    }

    /// A cubic lattice of nx × ny × nz particles of spacing 1 from the origin (cell centres),
    /// mass 1 (ρ = 1), smoothing length `h`.
    fn lattice(nx: usize, ny: usize, nz: usize, h: f64) -> Snapshot {
        let mut pos = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    pos.push([i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5]);
                }
            }
        }
        let n = pos.len();
        snapshot(
            3,
            &pos,
            &vec![1.0; n],
            &vec![h; n],
            [0.0; 3],
            [nx as f64, ny as f64, nz as f64],
        )
    }

    /// Largest relative deviation from `expected` over pixels whose centres lie inside the
    /// rectangle `inner`.
    fn max_rel_error(field: &[f64], frame: &Frame, inner: Extent, expected: f64) -> f64 {
        let mut worst: f64 = 0.0;
        let mut count = 0;
        for j in 0..frame.ny {
            for i in 0..frame.nx {
                let (x, y) = frame.centre(i, j);
                if x > inner.x.0 && x < inner.x.1 && y > inner.y.0 && y < inner.y.1 {
                    worst = worst.max((field[j * frame.nx + i] / expected - 1.0).abs());
                    count += 1;
                }
            }
        }
        assert!(count > 100, "only {count} pixels checked");
        worst
    }

    #[test]
    fn column_kernel_is_normalised() {
        for kind in KernelKind::ALL {
            let support = kind.support_factor();
            // The quadrature itself, before the table is renormalised.
            let (_, raw) = integrate_column_kernel(kind);
            eprintln!(
                "{kind:?}: column kernel quadrature ∫ F d²R − 1 = {:.2e}",
                raw - 1.0
            );
            assert!((raw - 1.0).abs() < 1e-4, "{kind:?}: {raw}");
            // F(0) = ∫ W₃(|z|) dz = 2 ∫₀^support W₃(s) ds; F(support · h) = 0.
            let unit = Kernel::<3>::of_kind(kind, 1.0);
            let n = 200_000;
            let ds = support / n as f64;
            let f0: f64 = 2.0
                * (0..n)
                    .map(|i| unit.w((i as f64 + 0.5) * ds) * ds)
                    .sum::<f64>();
            assert!(
                (column_kernel(kind, 0.0, 1.0) / f0 - 1.0).abs() < 1e-4,
                "{kind:?}"
            );
            assert_eq!(column_kernel(kind, support, 1.0), 0.0);
            assert!(
                (column_kernel(kind, 0.0, 0.5) / (4.0 * f0) - 1.0).abs() < 1e-4,
                "{kind:?}"
            );
            // Independent of the radial formula: sum F over a fine Cartesian grid.
            let h = 0.7;
            let n = 800;
            let d = 2.0 * support * h / n as f64;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let x = -support * h + (i as f64 + 0.5) * d;
                    let y = -support * h + (j as f64 + 0.5) * d;
                    sum += column_kernel(kind, (x * x + y * y).sqrt(), h) * d * d;
                }
            }
            assert!((sum - 1.0).abs() < 1e-5, "{kind:?}: {sum}");
        }
        // The cubic spline's closed form: F(0) = (2/π) ∫₀² w(q) dq = 1.5/π.
        assert!((column_kernel(KernelKind::Cubic, 0.0, 1.0) - 1.5 / PI).abs() < 1e-5);
    }

    #[test]
    fn slice_integral_matches_quadrature() {
        for kind in KernelKind::ALL {
            let support = kind.support_factor();
            let k3 = Kernel::<3>::of_kind(kind, 1.0);
            for frac in [0.0, 0.15, 0.495, 0.5, 0.7, 0.975] {
                let zeta = frac * support;
                // ∫ W₃(√(q² + ζ²)) 2πq dq by the midpoint rule.
                let n = 100_000;
                let qmax = (support * support - zeta * zeta).sqrt();
                let dq = qmax / n as f64;
                let num: f64 = (0..n)
                    .map(|i| {
                        let q = (i as f64 + 0.5) * dq;
                        k3.w((q * q + zeta * zeta).sqrt()) * 2.0 * PI * q * dq
                    })
                    .sum();
                assert!(
                    (slice_integral(kind, zeta) - num).abs() < 1e-8,
                    "{kind:?}: ζ = {zeta}"
                );
            }
            // The slices of a kernel add up to the kernel: ∫ G dζ = 1.
            let n = 100_000;
            let d = 2.0 * support / n as f64;
            let total: f64 = (0..n)
                .map(|i| slice_integral(kind, -support + (i as f64 + 0.5) * d) * d)
                .sum();
            assert!((total - 1.0).abs() < 1e-8, "{kind:?}: {total}");
            assert_eq!(slice_integral(kind, support), 0.0);
        }
        // The cubic spline's closed form, 2 ∫_ζ² w(r) r dr with its shape w.
        for z in [0.0f64, 0.5, 1.0, 1.5] {
            let t = 2.0 - z;
            let half = if z >= 1.0 {
                t.powi(4) / 8.0 - t.powi(5) / 20.0
            } else {
                0.35 - z * z / 2.0 + 3.0 * z.powi(4) / 8.0 - 3.0 * z.powi(5) / 20.0
            };
            // Simpson on 200 intervals per piece: error ~ (1/200)⁴ max|f⁗|/180 ≈ 1e-10.
            assert!((slice_integral(KernelKind::Cubic, z) - 2.0 * half).abs() < 1e-9);
        }
    }

    #[test]
    fn a_particle_is_drawn_with_its_runs_kernel() {
        // One particle of a 2D run with the quintic spline (support 3h): the picture is
        // m W₂(r) of that kernel, out to 3h, where the cubic spline's would end at 2h.
        let h = 0.1;
        let mut snap = Snapshot {
            dimension: 2,
            box_hi: [1.0, 1.0, 1.0],
            kernel: KernelKind::Quintic,
            ..Snapshot::default()
        };
        snap.id.push(0);
        for (d, x) in [0.5, 0.5, 0.0].into_iter().enumerate() {
            snap.pos[d].push(x);
            snap.vel[d].push(0.0);
        }
        snap.mass.push(1.0);
        snap.h.push(h);
        snap.rho.push(1.0);
        snap.u.push(0.0);
        snap.p.push(0.0);
        snap.diss.push(0.0);
        // 1000 pixels across [0, 1]: pixel centres at (k + 0.5)/1000.
        let frame = Frame::fit(Extent::new((0.0, 1.0), (0.0, 1.0)).unwrap(), (1000, 1000));
        let field = interpolate(&snap, Quantity::Density, View::FaceOn, &frame, None).unwrap();
        let w = Kernel::<2>::of_kind(KernelKind::Quintic, h);
        let row = 500;
        for i in [520, 600, 650, 720, 770] {
            let dx = (i as f64 + 0.5) / 1000.0 - 0.5;
            let dy = (row as f64 + 0.5) / 1000.0 - 0.5;
            let r = (dx * dx + dy * dy).sqrt();
            let got = field[row * frame.nx + i];
            // The footprint is renormalised to its pixel sum: 1e-3 covers that at 30
            // pixels per h.
            assert!(
                (got / w.w(r) - 1.0).abs() < 1e-3,
                "r = {r}: {got} against {}",
                w.w(r)
            );
        }
        // Past the support nothing.
        assert_eq!(field[row * frame.nx + 810], 0.0);
    }

    #[test]
    fn column_density_of_uniform_slab_equals_rho_times_thickness() {
        // 40 × 40 × 10 particles on a unit lattice: ρ = m/Δ³ = 1, thickness 10 → Σ = 10.
        // Along the line of sight each lattice column carries 10 particles, so the face-on
        // image is the 2D lattice sum of the column kernel F. That sum's discreteness error
        // is at most 2.5e-3 at h = 1.3Δ (2.9e-3 at 1.2Δ, 1.1e-3 at 1.5Δ, over all offsets
        // from the lattice); these pixel centres see 1.6e-3, well inside the 1% tolerance.
        // Pixels within 2h + Δ of the slab's sides, where the sum is truncated, are left out.
        let h = 1.3;
        let snap = lattice(40, 40, 10, h);
        let frame = Frame::new(Extent::new((0.0, 40.0), (0.0, 40.0)).unwrap(), 160, 160);
        let field = column_density(&snap, View::FaceOn, &frame).unwrap();
        let margin = 2.0 * h + 1.0;
        let inner = Extent::new((margin, 40.0 - margin), (margin, 40.0 - margin)).unwrap();
        let err = max_rel_error(&field, &frame, inner, 10.0);
        eprintln!("slab face-on column density: max relative error {err:.2e}");
        assert!(err < 0.01, "{err}");

        // Edge-on (along y, 40 deep): Σ = 40 inside the slab, nothing beyond its faces.
        let frame = Frame::new(Extent::new((0.0, 40.0), (-5.0, 15.0)).unwrap(), 160, 80);
        let field = column_density(&snap, View::EdgeOn, &frame).unwrap();
        let inner = Extent::new((margin, 40.0 - margin), (margin, 10.0 - margin)).unwrap();
        let err = max_rel_error(&field, &frame, inner, 40.0);
        eprintln!("slab edge-on column density: max relative error {err:.2e}");
        assert!(err < 0.01, "{err}");
        for j in 0..frame.ny {
            let (_, z) = frame.centre(0, j);
            if z > 10.0 + 2.0 * h || z < -2.0 * h {
                assert!(
                    field[j * frame.nx..(j + 1) * frame.nx]
                        .iter()
                        .all(|&v| v == 0.0)
                );
            }
        }
    }

    #[test]
    fn slice_density_of_uniform_lattice_equals_rho() {
        // The SPH density sum Σ m W₃ on a unit lattice at h = 1.3Δ, in the plane between
        // two lattice layers (z = 10) and on one (z = 10.5): ρ = 1 to the lattice sum's
        // discreteness, 3.6e-3 and 2.7e-3 at these pixel centres, well under 1%.
        let h = 1.3;
        let snap = lattice(20, 20, 20, h);
        let frame = Frame::new(Extent::new((0.0, 20.0), (0.0, 20.0)).unwrap(), 100, 100);
        let margin = 2.0 * h + 1.0;
        let inner = Extent::new((margin, 20.0 - margin), (margin, 20.0 - margin)).unwrap();
        for z in [10.0, 10.5] {
            let field = interpolate(&snap, Quantity::Density, View::Slice, &frame, Some(z));
            let err = max_rel_error(&field.unwrap(), &frame, inner, 1.0);
            eprintln!("lattice slice density at z = {z}: max relative error {err:.2e}");
            assert!(err < 0.01, "z = {z}: {err}");
        }
        // The default plane is the middle of the box, z = 10.
        let mid = interpolate(&snap, Quantity::Density, View::Slice, &frame, None).unwrap();
        let at10 = interpolate(&snap, Quantity::Density, View::Slice, &frame, Some(10.0));
        assert_eq!(mid, at10.unwrap());
    }

    /// A deterministic cloud: `n` particles uniform in [0.25, 0.75]² (and z in [0, 1] in 3D),
    /// masses in [0.5, 1.5], smoothing lengths in [0.002, 0.05].
    fn cloud(dimension: usize, n: usize, seed: u64) -> Snapshot {
        let mut rng = Rng::new(seed);
        let mut pos = Vec::with_capacity(n);
        let mut mass = Vec::with_capacity(n);
        let mut h = Vec::with_capacity(n);
        for _ in 0..n {
            let x = 0.25 + 0.5 * rng.uniform();
            let y = 0.25 + 0.5 * rng.uniform();
            let z = if dimension == 3 { rng.uniform() } else { 0.0 };
            pos.push([x, y, z]);
            mass.push(0.5 + rng.uniform());
            h.push(0.002 + 0.048 * rng.uniform());
        }
        let mut snap = snapshot(dimension, &pos, &mass, &h, [0.0; 3], [1.0; 3]);
        snap.rho = (0..n).map(|_| 0.5 + rng.uniform()).collect();
        snap.u = (0..n).map(|_| 2.5).collect();
        // P/ρ = 2.5 (to an ulp) for the temperature.
        snap.p = snap.rho.iter().map(|r| 2.5 * r).collect();
        snap
    }

    #[test]
    fn image_mass_equals_particle_mass() {
        // Pixels from much finer than h (footprints sampled and normalised) through
        // comparable (both kinds) to far coarser (every particle cloud-in-cell).
        let extent = Extent::new((0.0, 1.0), (0.0, 1.0)).unwrap();
        for dimension in [3, 2] {
            let snap = cloud(dimension, 3000, 17 + dimension as u64);
            let total: f64 = snap.mass.iter().sum();
            for n in [400, 200, 40, 6] {
                let frame = Frame::new(extent, n, n);
                let field = column_density(&snap, View::FaceOn, &frame).unwrap();
                let mass: f64 = field.iter().sum::<f64>() * frame.pixel_area();
                let err = (mass / total - 1.0).abs();
                eprintln!("{dimension}D, {n} × {n} pixels: image mass error {err:.2e}");
                assert!(err < 0.01, "{dimension}D, {n}²: {err}");
            }
        }
    }

    #[test]
    fn projected_average_of_uniform_field_is_that_value() {
        // A column-weighted mean of a constant is that constant wherever there is matter.
        let snap = cloud(3, 2000, 5);
        let frame = Frame::new(Extent::new((0.0, 1.0), (0.0, 1.0)).unwrap(), 64, 64);
        let u = interpolate(&snap, Quantity::Temperature, View::FaceOn, &frame, None).unwrap();
        let sigma = column_density(&snap, View::FaceOn, &frame).unwrap();
        for (a, s) in u.iter().zip(&sigma) {
            if *s > 0.0 {
                assert!((a - 2.5).abs() < 1e-12, "{a}");
            } else {
                assert_eq!(*a, 0.0);
            }
        }
        let (i, j) = (32, 32);
        assert!((u[j * 64 + i] - 2.5).abs() < 1e-12);
    }

    #[test]
    fn rendering_is_independent_of_the_thread_count() {
        let snap = cloud(3, 1500, 9);
        let frame = Frame::new(Extent::new((0.0, 1.0), (0.0, 1.0)).unwrap(), 90, 70);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    interpolate(&snap, Quantity::Velocity, View::EdgeOn, &frame, None).unwrap()
                })
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn rejects_1d_and_impossible_views() {
        let mut snap = cloud(3, 10, 1);
        let frame = Frame::new(Extent::new((0.0, 1.0), (0.0, 1.0)).unwrap(), 8, 8);
        let slice = interpolate(&snap, Quantity::ColumnDensity, View::Slice, &frame, None);
        assert!(slice.unwrap_err().to_string().contains("projection"));
        snap.dimension = 1;
        let e = column_density(&snap, View::FaceOn, &frame).unwrap_err();
        assert!(
            e.to_string().contains("1D runs are plotted as profiles"),
            "{e}"
        );
        snap.dimension = 2;
        assert!(column_density(&snap, View::EdgeOn, &frame).is_err());
        snap.dimension = 3;
        snap.h[3] = 0.0;
        assert!(column_density(&snap, View::FaceOn, &frame).is_err());
        snap.h[3] = 0.01;
        snap.rho.pop();
        assert!(column_density(&snap, View::FaceOn, &frame).is_err());
        for q in Quantity::ALL {
            assert_eq!(q.name().parse::<Quantity>().unwrap(), q);
        }
        for v in View::ALL {
            assert_eq!(v.name().parse::<View>().unwrap(), v);
        }
    }

    #[test]
    fn fit_keeps_pixels_square() {
        let e = Extent::new((-2.0, 2.0), (-0.5, 0.5)).unwrap();
        let f = Frame::fit(e, (512, 512));
        assert_eq!((f.nx, f.ny), (512, 128));
        assert!((f.dx() - f.dy()).abs() < 1e-12);
        let f = Frame::fit(e, (100, 10));
        assert_eq!((f.nx, f.ny), (40, 10));
    }

    #[test]
    fn default_frame_fits_the_particles_within_the_box() {
        // A ring of radius 1 about the centre of a box 20 wide: the frame is the ring
        // widened by one kernel support, not the box.
        let mut snap = Snapshot {
            dimension: 2,
            box_lo: [-10.0, -10.0, 0.0],
            box_hi: [10.0, 10.0, 1.0],
            ..Snapshot::default()
        };
        for k in 0..100 {
            let phi = std::f64::consts::TAU * k as f64 / 100.0;
            snap.pos[0].push(phi.cos());
            snap.pos[1].push(phi.sin());
            snap.pos[2].push(0.0);
            snap.h.push(0.1);
        }
        let e = Extent::default_for(&snap, View::FaceOn).unwrap();
        let pad = KernelKind::Cubic.support_factor() * 0.1;
        assert!(
            (e.x.0 + 1.0 + pad).abs() < 1e-12 && (e.x.1 - 1.0 - pad).abs() < 1e-12,
            "{e:?}"
        );
        assert!(
            (e.y.0 + 1.0 + pad).abs() < 1e-3 && (e.y.1 - 1.0 - pad).abs() < 1e-3,
            "{e:?}"
        );
        // Particles that fill the box (a periodic one) give the box.
        snap.pos[0][0] = -9.99;
        snap.pos[0][1] = 9.99;
        snap.pos[1][0] = -9.99;
        snap.pos[1][1] = 9.99;
        let e = Extent::default_for(&snap, View::FaceOn).unwrap();
        assert_eq!((e.x, e.y), ((-10.0, 10.0), (-10.0, 10.0)));
        let u = Extent::new((0.0, 1.0), (0.0, 1.0))
            .unwrap()
            .union(&Extent::new((-1.0, 0.5), (0.5, 2.0)).unwrap());
        assert_eq!((u.x, u.y), ((-1.0, 1.0), (0.0, 2.0)));
    }

    #[test]
    fn periodic_images_fill_the_borders() {
        // A uniform periodic lattice: without images its column density falls off within
        // one support of the faces; with them it is uniform up to the faces.
        let snap = lattice(12, 12, 4, 1.2);
        let frame = Frame::new(Extent::new((0.0, 12.0), (0.0, 12.0)).unwrap(), 24, 24);
        let plain = column_density(&snap, View::FaceOn, &frame).unwrap();
        let imaged = with_periodic_images(&snap, View::FaceOn);
        assert!(imaged.len() > snap.len());
        // Images only within one support of a face, across x and y only.
        for i in snap.len()..imaged.len() {
            let x = imaged.pos[0][i];
            let y = imaged.pos[1][i];
            assert!(
                !((0.0..12.0).contains(&x) && (0.0..12.0).contains(&y)),
                "{x} {y}"
            );
        }
        let full = column_density(&imaged, View::FaceOn, &frame).unwrap();
        let spread = |f: &[f64]| {
            let (lo, hi) = f
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(l, h), &v| (l.min(v), h.max(v)));
            (hi - lo) / hi
        };
        assert!(spread(&plain) > 0.3, "{}", spread(&plain));
        assert!(spread(&full) < 0.02, "{}", spread(&full));
    }

    #[test]
    fn a_slice_near_a_face_takes_the_images_across_the_line_of_sight() {
        // The same lattice, 8 layers deep: a slice 0.05 above the bottom face cuts the
        // kernels of the top layers' images (z − 8), a projection must not count them.
        let snap = lattice(12, 12, 8, 1.2);
        let frame = Frame::new(Extent::new((3.0, 9.0), (3.0, 9.0)).unwrap(), 12, 12);
        let slice = |s: &Snapshot, z: f64| {
            let f = interpolate(s, Quantity::Density, View::Slice, &frame, Some(z)).unwrap();
            f.iter().sum::<f64>() / f.len() as f64
        };
        let imaged = with_periodic_images(&snap, View::Slice);
        // The middle of the box (no face within reach) is the reference density, ≈ 1.
        let mid = slice(&snap, 4.0);
        assert!((mid - 1.0).abs() < 0.02, "{mid}");
        // Near the face: the images restore it; without them a third of it is missing.
        let near_plain = slice(&snap, 0.05);
        let near_imaged = slice(&imaged, 0.05);
        assert!(near_plain < 0.8 * mid, "{near_plain} vs {mid}");
        assert!(
            (near_imaged / mid - 1.0).abs() < 0.02,
            "{near_imaged} vs {mid}"
        );
        // A face-on projection takes no images along z.
        let projected = with_periodic_images(&snap, View::FaceOn);
        for i in snap.len()..projected.len() {
            assert!((0.0..8.0).contains(&projected.pos[2][i]));
        }
    }
}
