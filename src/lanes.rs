//! Numbers the pair functions are written over: `f64` for one pair, [`F64x2`] for two pairs
//! in the two lanes of one SSE2 register (x86-64's baseline; two plain `f64` elsewhere).
//!
//! The physics of a pair ([`crate::physics::hydro::force_pair`]) is written once over
//! [`Real`]; the force sum calls it with `F64x2` for its pairs two at a time, so that each
//! arithmetic instruction serves two pairs, and pair finding so takes the cubic spline's
//! W and F ([`crate::kernel::Kernel::w_and_f_two`]). Every operation is IEEE 754 lane by
//! lane, the selections are masks that give what the scalar comparisons give (NaN
//! included), and nothing is fused or reordered: lane `l` of a result is, to the bit, what
//! the same code gives with `f64` on lane `l`'s inputs (the unit tests below,
//! `force_pair_in_lanes_is_the_scalar_force_to_the_bit` and
//! `kernel_values_two_at_once_are_those_one_at_a_time_to_the_bit`).

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A number, or a bundle of `LANES` numbers computed alike.
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
{
    const LANES: usize;
    /// Every lane `x`.
    fn splat(x: f64) -> Self;
    /// Lane `l`.
    fn lane(self, l: usize) -> f64;
    /// Lane `l` from `f(l)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// Two bundles from a function giving both values of lane `l`.
    fn from_fn2(f: impl FnMut(usize) -> (f64, f64)) -> (Self, Self);
    /// `a` in the lanes where `self > 0`, +0 elsewhere (NaN: +0).
    fn where_positive(self, a: Self) -> Self;
    /// `a` in the lanes where `self < 0`, +0 elsewhere (NaN: +0).
    fn where_negative(self, a: Self) -> Self;
    /// `a()` in the lanes where `self < bound`, `b()` elsewhere (NaN: `b()`): for `f64` a
    /// branch that evaluates one of them, with lanes both evaluated and selected by a mask.
    fn if_less(self, bound: f64, a: impl FnOnce() -> Self, b: impl FnOnce() -> Self) -> Self;
}

impl Real for f64 {
    const LANES: usize = 1;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0)
    }
    #[inline(always)]
    fn from_fn2(mut f: impl FnMut(usize) -> (f64, f64)) -> (Self, Self) {
        f(0)
    }
    #[inline(always)]
    fn where_positive(self, a: Self) -> Self {
        if self > 0.0 { a } else { 0.0 }
    }
    #[inline(always)]
    fn where_negative(self, a: Self) -> Self {
        if self < 0.0 { a } else { 0.0 }
    }
    #[inline(always)]
    fn if_less(self, bound: f64, a: impl FnOnce() -> Self, b: impl FnOnce() -> Self) -> Self {
        if self < bound { a() } else { b() }
    }
}

/// Two `f64` lanes.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct F64x2(imp::V);

impl F64x2 {
    /// Lane 0 `a`, lane 1 `b`.
    #[inline(always)]
    pub fn new(a: f64, b: f64) -> Self {
        Self(imp::new(a, b))
    }
    /// Both lanes.
    #[inline(always)]
    pub fn to_array(self) -> [f64; 2] {
        imp::to_array(self.0)
    }
}

impl Real for F64x2 {
    const LANES: usize = 2;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Self::new(x, x)
    }
    #[inline(always)]
    fn lane(self, l: usize) -> f64 {
        self.to_array()[l]
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        Self::new(f(0), f(1))
    }
    #[inline(always)]
    fn from_fn2(mut f: impl FnMut(usize) -> (f64, f64)) -> (Self, Self) {
        let (a0, b0) = f(0);
        let (a1, b1) = f(1);
        (Self::new(a0, a1), Self::new(b0, b1))
    }
    #[inline(always)]
    fn where_positive(self, a: Self) -> Self {
        Self(imp::where_gt0(self.0, a.0))
    }
    #[inline(always)]
    fn where_negative(self, a: Self) -> Self {
        Self(imp::where_lt0(self.0, a.0))
    }
    #[inline(always)]
    fn if_less(self, bound: f64, a: impl FnOnce() -> Self, b: impl FnOnce() -> Self) -> Self {
        Self(imp::select_lt(self.0, Self::splat(bound).0, a().0, b().0))
    }
}

/// `$tr` (and `$atr`, the assigning form, where given) of `F64x2` as `imp::$imp`.
macro_rules! lane_op {
    ($tr:ident, $f:ident, $imp:ident) => {
        impl $tr for F64x2 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(imp::$imp(self.0, o.0))
            }
        }
    };
    ($tr:ident, $f:ident, $imp:ident, $atr:ident, $af:ident) => {
        lane_op!($tr, $f, $imp);
        impl $atr for F64x2 {
            #[inline(always)]
            fn $af(&mut self, o: Self) {
                *self = Self(imp::$imp(self.0, o.0));
            }
        }
    };
}
lane_op!(Add, add, add, AddAssign, add_assign);
lane_op!(Sub, sub, sub, SubAssign, sub_assign);
lane_op!(Mul, mul, mul);
lane_op!(Div, div, div);

impl Neg for F64x2 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self(imp::neg(self.0))
    }
}

/// SSE2, part of every x86-64 processor: the intrinsics need no runtime check.
#[cfg(target_arch = "x86_64")]
mod imp {
    use std::arch::x86_64::*;
    pub type V = __m128d;

    #[inline(always)]
    pub fn new(a: f64, b: f64) -> V {
        // SAFETY: SSE2 is enabled on every x86-64 target.
        unsafe { _mm_set_pd(b, a) }
    }
    #[inline(always)]
    pub fn to_array(v: V) -> [f64; 2] {
        // SAFETY: `__m128d` and `[f64; 2]` have the same size; any bits are valid f64.
        unsafe { std::mem::transmute::<V, [f64; 2]>(v) }
    }
    #[inline(always)]
    pub fn add(a: V, b: V) -> V {
        // SAFETY: SSE2 (as above).
        unsafe { _mm_add_pd(a, b) }
    }
    #[inline(always)]
    pub fn sub(a: V, b: V) -> V {
        // SAFETY: SSE2 (as above).
        unsafe { _mm_sub_pd(a, b) }
    }
    #[inline(always)]
    pub fn mul(a: V, b: V) -> V {
        // SAFETY: SSE2 (as above).
        unsafe { _mm_mul_pd(a, b) }
    }
    #[inline(always)]
    pub fn div(a: V, b: V) -> V {
        // SAFETY: SSE2 (as above).
        unsafe { _mm_div_pd(a, b) }
    }
    #[inline(always)]
    pub fn neg(a: V) -> V {
        // Flips the sign bit, as `-x` does on an f64.
        // SAFETY: SSE2 (as above).
        unsafe { _mm_xor_pd(a, _mm_set1_pd(-0.0)) }
    }
    #[inline(always)]
    pub fn where_gt0(c: V, a: V) -> V {
        // The ordered comparison is false for NaN, as `c > 0.0` is.
        // SAFETY: SSE2 (as above).
        unsafe { _mm_and_pd(_mm_cmpgt_pd(c, _mm_setzero_pd()), a) }
    }
    #[inline(always)]
    pub fn where_lt0(c: V, a: V) -> V {
        // SAFETY: SSE2 (as above).
        unsafe { _mm_and_pd(_mm_cmplt_pd(c, _mm_setzero_pd()), a) }
    }
    #[inline(always)]
    pub fn select_lt(c: V, bound: V, a: V, b: V) -> V {
        // The ordered comparison is false for NaN, as `c < bound` is; the blend moves bits.
        // SAFETY: SSE2 (as above).
        unsafe {
            let m = _mm_cmplt_pd(c, bound);
            _mm_or_pd(_mm_and_pd(m, a), _mm_andnot_pd(m, b))
        }
    }
}

/// Elsewhere: two plain lanes.
#[cfg(not(target_arch = "x86_64"))]
mod imp {
    pub type V = [f64; 2];

    #[inline(always)]
    pub fn new(a: f64, b: f64) -> V {
        [a, b]
    }
    #[inline(always)]
    pub fn to_array(v: V) -> [f64; 2] {
        v
    }
    #[inline(always)]
    pub fn add(a: V, b: V) -> V {
        [a[0] + b[0], a[1] + b[1]]
    }
    #[inline(always)]
    pub fn sub(a: V, b: V) -> V {
        [a[0] - b[0], a[1] - b[1]]
    }
    #[inline(always)]
    pub fn mul(a: V, b: V) -> V {
        [a[0] * b[0], a[1] * b[1]]
    }
    #[inline(always)]
    pub fn div(a: V, b: V) -> V {
        [a[0] / b[0], a[1] / b[1]]
    }
    #[inline(always)]
    pub fn neg(a: V) -> V {
        [-a[0], -a[1]]
    }
    #[inline(always)]
    pub fn where_gt0(c: V, a: V) -> V {
        [
            if c[0] > 0.0 { a[0] } else { 0.0 },
            if c[1] > 0.0 { a[1] } else { 0.0 },
        ]
    }
    #[inline(always)]
    pub fn where_lt0(c: V, a: V) -> V {
        [
            if c[0] < 0.0 { a[0] } else { 0.0 },
            if c[1] < 0.0 { a[1] } else { 0.0 },
        ]
    }
    #[inline(always)]
    pub fn select_lt(c: V, bound: V, a: V, b: V) -> V {
        [
            if c[0] < bound[0] { a[0] } else { b[0] },
            if c[1] < bound[1] { a[1] } else { b[1] },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Awkward values: signed zeros, NaN, infinities, subnormals, ordinary numbers.
    const VALUES: [f64; 12] = [
        0.0,
        -0.0,
        1.0,
        -1.5,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE / 4.0,
        -3.0e-310,
        1.0e300,
        0.1,
        -7.25e-3,
    ];

    /// The scalar operation a lane must match.
    type Scalar = fn(f64, f64) -> f64;

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    #[test]
    fn every_lane_operation_is_the_scalar_one_to_the_bit() {
        for &a in &VALUES {
            for &b in &VALUES {
                for &c in &VALUES {
                    // Lane 0 holds (a, b), lane 1 (b, c): the lanes must not mix.
                    let x = F64x2::new(a, b);
                    let y = F64x2::new(b, c);
                    let pairs = [(a, b), (b, c)];
                    let ops: [(F64x2, Scalar); 7] = [
                        (x + y, |p, q| p + q),
                        (x - y, |p, q| p - q),
                        (x * y, |p, q| p * q),
                        (x / y, |p, q| p / q),
                        (-x, |p, _| -p),
                        (x.where_positive(y), |p, q| p.where_positive(q)),
                        (x.where_negative(y), |p, q| p.where_negative(q)),
                    ];
                    for (v, scalar) in ops {
                        for (l, &(p, q)) in pairs.iter().enumerate() {
                            let want = scalar(p, q);
                            assert!(
                                same(v.lane(l), want),
                                "lane {l} of ({p}, {q}): {} against {want}",
                                v.lane(l)
                            );
                        }
                    }
                    let mut s = x;
                    s += y;
                    assert!(same(s.lane(0), a + b) && same(s.lane(1), b + c));
                    let mut s = x;
                    s -= y;
                    assert!(same(s.lane(0), a - b) && same(s.lane(1), b - c));
                }
            }
        }
    }

    #[test]
    fn a_comparison_selects_lane_by_lane_what_the_scalar_branch_takes() {
        for &c in &VALUES {
            for &bound in &VALUES {
                for (&a, &b) in VALUES.iter().zip(VALUES.iter().rev()) {
                    let x = F64x2::new(c, bound).if_less(
                        bound,
                        || F64x2::new(a, b),
                        || F64x2::new(b, a),
                    );
                    let want = [
                        c.if_less(bound, || a, || b),
                        bound.if_less(bound, || b, || a),
                    ];
                    for l in 0..2 {
                        assert!(
                            same(x.lane(l), want[l]),
                            "lane {l} of {c} < {bound}: {} against {}",
                            x.lane(l),
                            want[l]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_selection_gives_positive_zero_where_the_scalar_comparison_fails() {
        let sel = F64x2::new(f64::NAN, -0.0).where_negative(F64x2::new(-2.0, -2.0));
        assert_eq!(sel.to_array().map(f64::to_bits), [0.0f64.to_bits(); 2]);
        let sel = F64x2::new(0.0, 1.0).where_positive(F64x2::new(-0.0, -0.0));
        assert_eq!(sel.lane(0).to_bits(), 0.0f64.to_bits());
        assert_eq!(sel.lane(1).to_bits(), (-0.0f64).to_bits());
    }

    #[test]
    fn lanes_come_from_and_go_to_their_places() {
        let v = F64x2::from_fn(|l| l as f64 + 0.5);
        assert_eq!(v.to_array(), [0.5, 1.5]);
        let (p, q) = F64x2::from_fn2(|l| (l as f64, -(l as f64)));
        assert_eq!((p.to_array(), q.to_array()), ([0.0, 1.0], [0.0, -1.0]));
        assert_eq!(F64x2::splat(3.0).to_array(), [3.0, 3.0]);
        assert_eq!(<f64 as Real>::from_fn(|l| l as f64 + 2.0), 2.0);
    }
}
