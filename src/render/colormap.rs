//! Colour maps and colour ranges: perceptually uniform palettes (viridis, magma) as tables of
//! anchor colours interpolated linearly, and the mapping of a field value to a position
//! t ∈ [0, 1] on the palette, linear or logarithmic.

use std::fmt;
use std::str::FromStr;

use anyhow::{Result, bail};

/// A perceptually uniform palette with monotonically increasing luminance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Colormap {
    /// Blue-green-yellow (matplotlib's default): fields such as u, |v|, dissipation.
    #[default]
    Viridis,
    /// Black-purple-orange-cream: column density and density, whose log images span decades.
    Magma,
}

impl Colormap {
    pub const ALL: [Colormap; 2] = [Colormap::Viridis, Colormap::Magma];

    pub fn name(self) -> &'static str {
        match self {
            Colormap::Viridis => "viridis",
            Colormap::Magma => "magma",
        }
    }

    /// The anchor colours, sRGB components in [0, 1], evenly spaced in t.
    pub fn anchors(self) -> &'static [[f64; 3]] {
        match self {
            Colormap::Viridis => &VIRIDIS,
            Colormap::Magma => &MAGMA,
        }
    }

    /// The colour at `t` as sRGB components in [0, 1]; `t` is clamped to [0, 1] and NaN gives
    /// the bottom colour.
    pub fn rgb_f64(self, t: f64) -> [f64; 3] {
        let a = self.anchors();
        let n = a.len() - 1;
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let x = t * n as f64;
        let k = (x as usize).min(n - 1);
        let f = x - k as f64;
        std::array::from_fn(|c| a[k][c] + (a[k + 1][c] - a[k][c]) * f)
    }

    /// The colour at `t` as 8-bit sRGB.
    pub fn rgb(self, t: f64) -> [u8; 3] {
        self.rgb_f64(t).map(|c| (c * 255.0).round() as u8)
    }
}

impl fmt::Display for Colormap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Colormap {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        match Colormap::ALL.into_iter().find(|c| c.name() == s) {
            Some(c) => Ok(c),
            None => bail!("unknown colour map {s:?}: expected viridis or magma"),
        }
    }
}

/// How values map onto the palette.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scale {
    #[default]
    Linear,
    /// log10 of the value; values ≤ 0 take the bottom colour.
    Log,
}

impl Scale {
    pub fn name(self) -> &'static str {
        match self {
            Scale::Linear => "linear",
            Scale::Log => "log",
        }
    }
}

impl fmt::Display for Scale {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Scale {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "linear" | "lin" => Ok(Scale::Linear),
            "log" | "log10" => Ok(Scale::Log),
            _ => bail!("unknown colour scale {s:?}: expected linear or log"),
        }
    }
}

/// The values at the bottom (`lo`) and top (`hi`) of the palette, and the scale between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorRange {
    pub lo: f64,
    pub hi: f64,
    pub scale: Scale,
}

impl ColorRange {
    /// A range, checked: finite, `lo < hi`, and `lo > 0` on a log scale.
    pub fn new(lo: f64, hi: f64, scale: Scale) -> Result<Self> {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            bail!("colour range must be finite with lo < hi, got {lo} .. {hi}");
        }
        if scale == Scale::Log && !(lo > 0.0) {
            bail!("a log colour range needs lo > 0, got {lo} .. {hi}");
        }
        Ok(Self { lo, hi, scale })
    }

    /// Position of `v` on the palette, clamped to [0, 1]. Log scale: `v ≤ 0` (and NaN) → 0.
    pub fn t(&self, v: f64) -> f64 {
        let t = match self.scale {
            Scale::Linear => (v - self.lo) / (self.hi - self.lo),
            Scale::Log => {
                if !(v > 0.0) {
                    return 0.0;
                }
                (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
            }
        };
        if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) }
    }

    /// The axis value of `v` for a colour bar: `v` itself, or log10 `v` on a log scale.
    pub fn axis_value(&self, v: f64) -> f64 {
        match self.scale {
            Scale::Linear => v,
            Scale::Log => v.log10(),
        }
    }
}

/// Viridis (van der Walt, Smith & Firing; matplotlib, CC0): every fifth entry of the
/// 256-colour table, 52 anchors; linear interpolation is within 1/255 of the full table.
const VIRIDIS: [[f64; 3]; 52] = [
    [0.267004, 0.004874, 0.329415],
    [0.273809, 0.031497, 0.358853],
    [0.278791, 0.062145, 0.386592],
    [0.281924, 0.089666, 0.412415],
    [0.283197, 0.115680, 0.436115],
    [0.282623, 0.140926, 0.457517],
    [0.280255, 0.165693, 0.476498],
    [0.276194, 0.190074, 0.493001],
    [0.270595, 0.214069, 0.507052],
    [0.263663, 0.237631, 0.518762],
    [0.255645, 0.260703, 0.528312],
    [0.246811, 0.283237, 0.535941],
    [0.237441, 0.305202, 0.541921],
    [0.227802, 0.326594, 0.546532],
    [0.218130, 0.347432, 0.550038],
    [0.208623, 0.367752, 0.552675],
    [0.199430, 0.387607, 0.554642],
    [0.190631, 0.407061, 0.556089],
    [0.182256, 0.426184, 0.557120],
    [0.174274, 0.445044, 0.557792],
    [0.166617, 0.463708, 0.558119],
    [0.159194, 0.482237, 0.558073],
    [0.151918, 0.500685, 0.557587],
    [0.144759, 0.519093, 0.556572],
    [0.137770, 0.537492, 0.554906],
    [0.131172, 0.555899, 0.552459],
    [0.125394, 0.574318, 0.549086],
    [0.121148, 0.592739, 0.544641],
    [0.119423, 0.611141, 0.538982],
    [0.121380, 0.629492, 0.531973],
    [0.128087, 0.647749, 0.523491],
    [0.140210, 0.665859, 0.513427],
    [0.157851, 0.683765, 0.501686],
    [0.180653, 0.701402, 0.488189],
    [0.208030, 0.718701, 0.472873],
    [0.239374, 0.735588, 0.455688],
    [0.274149, 0.751988, 0.436601],
    [0.311925, 0.767822, 0.415586],
    [0.352360, 0.783011, 0.392636],
    [0.395174, 0.797475, 0.367757],
    [0.440137, 0.811138, 0.340967],
    [0.487026, 0.823929, 0.312321],
    [0.535621, 0.835785, 0.281908],
    [0.585678, 0.846661, 0.249897],
    [0.636902, 0.856542, 0.216620],
    [0.688944, 0.865448, 0.182725],
    [0.741388, 0.873449, 0.149561],
    [0.793760, 0.880678, 0.120005],
    [0.845561, 0.887322, 0.099702],
    [0.896320, 0.893616, 0.096335],
    [0.945636, 0.899815, 0.112838],
    [0.993248, 0.906157, 0.143936],
];

/// Magma (Smith & van der Walt; matplotlib, CC0): every fifth entry of the 256-colour table.
const MAGMA: [[f64; 3]; 52] = [
    [0.001462, 0.000466, 0.013866],
    [0.007588, 0.006356, 0.044973],
    [0.018815, 0.016026, 0.084584],
    [0.035520, 0.028397, 0.125209],
    [0.056615, 0.042160, 0.167446],
    [0.078815, 0.054184, 0.211667],
    [0.102815, 0.063010, 0.257854],
    [0.129380, 0.067935, 0.305443],
    [0.159018, 0.068354, 0.352688],
    [0.191460, 0.064818, 0.396152],
    [0.225302, 0.060445, 0.431742],
    [0.258857, 0.059706, 0.457710],
    [0.291366, 0.064553, 0.475462],
    [0.322899, 0.073782, 0.487408],
    [0.353773, 0.085373, 0.495501],
    [0.384299, 0.097855, 0.501002],
    [0.414709, 0.110431, 0.504662],
    [0.445163, 0.122724, 0.506901],
    [0.475780, 0.134577, 0.507921],
    [0.506629, 0.145958, 0.507806],
    [0.537755, 0.156894, 0.506551],
    [0.569172, 0.167454, 0.504105],
    [0.600868, 0.177743, 0.500394],
    [0.632805, 0.187893, 0.495332],
    [0.664915, 0.198075, 0.488836],
    [0.697098, 0.208501, 0.480835],
    [0.729216, 0.219437, 0.471279],
    [0.761077, 0.231214, 0.460162],
    [0.792427, 0.244242, 0.447543],
    [0.822926, 0.259016, 0.433573],
    [0.852126, 0.276106, 0.418573],
    [0.879464, 0.296125, 0.403118],
    [0.904281, 0.319610, 0.388137],
    [0.925937, 0.346844, 0.374959],
    [0.944006, 0.377643, 0.365136],
    [0.958464, 0.411324, 0.360014],
    [0.969680, 0.446936, 0.360311],
    [0.978210, 0.483612, 0.366025],
    [0.984622, 0.520713, 0.376698],
    [0.989363, 0.557873, 0.391671],
    [0.992785, 0.594891, 0.410283],
    [0.995122, 0.631696, 0.431951],
    [0.996580, 0.668256, 0.456192],
    [0.997254, 0.704611, 0.482635],
    [0.997285, 0.740772, 0.510983],
    [0.996727, 0.776795, 0.541039],
    [0.995680, 0.812706, 0.572645],
    [0.994222, 0.848540, 0.605696],
    [0.992440, 0.884330, 0.640099],
    [0.990570, 0.920049, 0.675675],
    [0.988717, 0.955742, 0.712242],
    [0.987053, 0.991438, 0.749504],
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative luminance of an sRGB colour (Rec. 709 weights on linearised components).
    fn luminance(c: [f64; 3]) -> f64 {
        let lin = |v: f64| {
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        0.2126 * lin(c[0]) + 0.7152 * lin(c[1]) + 0.0722 * lin(c[2])
    }

    #[test]
    fn colormap_endpoints_and_monotone_luminance() {
        assert_eq!(Colormap::Viridis.rgb(0.0), [68, 1, 84]);
        assert_eq!(Colormap::Viridis.rgb(1.0), [253, 231, 37]);
        assert_eq!(Colormap::Magma.rgb(0.0), [0, 0, 4]);
        assert_eq!(Colormap::Magma.rgb(1.0), [252, 253, 191]);
        for map in Colormap::ALL {
            assert!(map.anchors().len() >= 16);
            // Out of range and NaN clamp to the ends.
            assert_eq!(map.rgb(-3.0), map.rgb(0.0));
            assert_eq!(map.rgb(7.0), map.rgb(1.0));
            assert_eq!(map.rgb(f64::NAN), map.rgb(0.0));
            // Perceptual order: luminance rises strictly from bottom to top.
            let n = 4000;
            let mut prev = luminance(map.rgb_f64(0.0));
            for i in 1..=n {
                let y = luminance(map.rgb_f64(i as f64 / n as f64));
                assert!(
                    y > prev,
                    "{map}: luminance falls at t = {}",
                    i as f64 / n as f64
                );
                prev = y;
            }
            assert_eq!(map.name().parse::<Colormap>().unwrap(), map);
        }
    }

    #[test]
    fn linear_range_maps_ends_and_middle() {
        let r = ColorRange::new(-2.0, 6.0, Scale::Linear).unwrap();
        assert_eq!(r.t(-2.0), 0.0);
        assert_eq!(r.t(6.0), 1.0);
        assert_eq!(r.t(2.0), 0.5);
        assert_eq!(r.t(-100.0), 0.0);
        assert_eq!(r.t(100.0), 1.0);
        assert!(ColorRange::new(1.0, 1.0, Scale::Linear).is_err());
        assert!(ColorRange::new(f64::NAN, 1.0, Scale::Linear).is_err());
    }

    #[test]
    fn log_scale_maps_nonpositive_to_bottom() {
        let r = ColorRange::new(1e-3, 10.0, Scale::Log).unwrap();
        assert_eq!(r.t(0.0), 0.0);
        assert_eq!(r.t(-5.0), 0.0);
        assert_eq!(r.t(f64::NAN), 0.0);
        assert_eq!(r.t(1e-9), 0.0);
        assert!((r.t(1e-3)).abs() < 1e-12);
        assert!((r.t(10.0) - 1.0).abs() < 1e-12);
        assert!((r.t(0.1) - 0.5).abs() < 1e-12);
        assert!(ColorRange::new(0.0, 10.0, Scale::Log).is_err());
        assert!(ColorRange::new(-1.0, 10.0, Scale::Log).is_err());
        assert_eq!("log".parse::<Scale>().unwrap(), Scale::Log);
    }
}
