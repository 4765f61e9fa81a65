//! The wide solver's lanes: four or eight [`Real`]s worked on side by side.
//!
//! [`Wide`] is what the kernels in `wide.rs` ask of a lane type. Two types provide it:
//! [`Lanes`] (glam's four-wide vector, SSE2 on x86-64) and [`Lanes8`] (eight lanes, written as
//! plain per-lane loops that the compiler turns into AVX2 instructions inside the kernels
//! compiled for AVX2). Every operation is the same IEEE operation lane by lane in both, and
//! `max`/`min` follow SSE's rule (the second operand unless the first is strictly greater,
//! resp. smaller), so a contact's arithmetic, and the World's result, does not depend on how
//! many contacts share a bundle.

use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, Neg, Sub, SubAssign};

use crate::physics::math::{Lanes, Real};

/// A lane type for the wide kernels: `WIDTH` independent [`Real`]s.
pub(crate) trait Wide:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
{
    /// How many lanes.
    const WIDTH: usize;
    /// Every lane 0.
    const ZERO: Self;
    /// Every lane 1.
    const ONE: Self;
    /// A lane-wise truth value, from a comparison.
    type Mask: Copy + BitAnd<Output = Self::Mask> + BitOr<Output = Self::Mask>;
    /// One `u32` per lane (contact and body indices).
    type Index: Copy + AsRef<[u32]> + AsMut<[u32]>;
    /// The lanes as plain numbers.
    type Array: Copy + AsRef<[Real]>;
    /// Every lane `x`.
    fn splat(x: Real) -> Self;
    /// Every index lane `i`.
    fn index_splat(i: u32) -> Self::Index;
    /// Set lane `i` to `x`, in place (packing writes each lane once, where it lives).
    fn set_lane(&mut self, i: usize, x: Real);
    /// All lanes as plain numbers.
    fn to_lanes(self) -> Self::Array;
    /// Lane-wise `if self > rhs { self } else { rhs }` (SSE's `maxps`).
    fn max(self, rhs: Self) -> Self;
    /// Lane-wise `if self < rhs { self } else { rhs }` (SSE's `minps`).
    fn min(self, rhs: Self) -> Self;
    /// Lane-wise `self > rhs`.
    fn cmpgt(self, rhs: Self) -> Self::Mask;
    /// Lane-wise `self >= rhs`.
    fn cmpge(self, rhs: Self) -> Self::Mask;
    /// Lane-wise `if mask { if_true } else { if_false }`.
    fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self;
    /// Whether any lane of `mask` is true.
    fn any(mask: Self::Mask) -> bool;
    /// The eight columns of `WIDTH` rows of eight numbers, lane i of column k being `row(i)[k]`:
    /// a transpose, so that what is laid out per body (row) comes out per field (column).
    fn columns<'a>(row: impl Fn(usize) -> &'a [Real; 8]) -> [Self; 8];
    /// The inverse for four columns: lane i of column k becomes word k of `rows[idx[i]]`
    /// (words 4-7 untouched). Where lanes name the same row, the last lane's words stay.
    fn scatter_rows<R: AsMut<[Real; 8]>>(columns: [Self; 4], rows: &mut [R], idx: &Self::Index);

    /// `self.max(lo).min(hi)`, as glam's `clamp`.
    #[inline(always)]
    fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
}

#[cfg(not(feature = "f64"))]
type LanesMask = glam::BVec4A;
#[cfg(feature = "f64")]
type LanesMask = glam::BVec4;

/// `Wide`'s binary methods on glam's lanes: glam's own (SSE's `maxps`, `cmpgtps`, ...).
macro_rules! forward_to_glam {
    ($($name:ident -> $out:ty),*) => {
        $(
            #[inline(always)]
            fn $name(self, rhs: Self) -> $out {
                Lanes::$name(self, rhs)
            }
        )*
    };
}

impl Wide for Lanes {
    const WIDTH: usize = 4;
    const ZERO: Self = Lanes::ZERO;
    const ONE: Self = Lanes::ONE;
    type Mask = LanesMask;
    type Index = [u32; 4];
    type Array = [Real; 4];
    #[inline(always)]
    fn splat(x: Real) -> Self {
        Lanes::splat(x)
    }
    #[inline(always)]
    fn index_splat(i: u32) -> [u32; 4] {
        [i; 4]
    }
    #[inline(always)]
    fn set_lane(&mut self, i: usize, x: Real) {
        self[i] = x;
    }
    #[inline(always)]
    fn to_lanes(self) -> [Real; 4] {
        self.to_array()
    }
    forward_to_glam!(max -> Self, min -> Self, cmpgt -> LanesMask, cmpge -> LanesMask);
    #[inline(always)]
    fn select(mask: LanesMask, if_true: Self, if_false: Self) -> Self {
        Lanes::select(mask, if_true, if_false)
    }
    #[inline(always)]
    fn any(mask: LanesMask) -> bool {
        mask.any()
    }
    #[inline(always)]
    fn columns<'a>(row: impl Fn(usize) -> &'a [Real; 8]) -> [Self; 8] {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        {
            use std::arch::x86_64::{
                __m128, _mm_loadu_ps, _mm_movehl_ps, _mm_movelh_ps, _mm_unpackhi_ps,
                _mm_unpacklo_ps,
            };
            // SAFETY: SSE is part of x86-64, and each load reads four of a row's eight f32s.
            unsafe {
                let (r0, r1, r2, r3) = (
                    row(0).as_ptr(),
                    row(1).as_ptr(),
                    row(2).as_ptr(),
                    row(3).as_ptr(),
                );
                // Fields 0-3 and 4-7 apart, each a 4x4 transpose: pairs of rows interleaved,
                // then their halves joined. (Spelled out: no closure may stand between the
                // kernels and these instructions.)
                let (a0, a1) = (_mm_loadu_ps(r0), _mm_loadu_ps(r1));
                let (a2, a3) = (_mm_loadu_ps(r2), _mm_loadu_ps(r3));
                let (b0, b1) = (_mm_loadu_ps(r0.add(4)), _mm_loadu_ps(r1.add(4)));
                let (b2, b3) = (_mm_loadu_ps(r2.add(4)), _mm_loadu_ps(r3.add(4)));
                let (t0, t1) = (_mm_unpacklo_ps(a0, a1), _mm_unpacklo_ps(a2, a3));
                let (t2, t3) = (_mm_unpackhi_ps(a0, a1), _mm_unpackhi_ps(a2, a3));
                let (u0, u1) = (_mm_unpacklo_ps(b0, b1), _mm_unpacklo_ps(b2, b3));
                let (u2, u3) = (_mm_unpackhi_ps(b0, b1), _mm_unpackhi_ps(b2, b3));
                let columns: [__m128; 8] = [
                    _mm_movelh_ps(t0, t1),
                    _mm_movehl_ps(t1, t0),
                    _mm_movelh_ps(t2, t3),
                    _mm_movehl_ps(t3, t2),
                    _mm_movelh_ps(u0, u1),
                    _mm_movehl_ps(u1, u0),
                    _mm_movelh_ps(u2, u3),
                    _mm_movehl_ps(u3, u2),
                ];
                [
                    Lanes::from(columns[0]),
                    Lanes::from(columns[1]),
                    Lanes::from(columns[2]),
                    Lanes::from(columns[3]),
                    Lanes::from(columns[4]),
                    Lanes::from(columns[5]),
                    Lanes::from(columns[6]),
                    Lanes::from(columns[7]),
                ]
            }
        }
        #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
        {
            let rows = [row(0), row(1), row(2), row(3)];
            [0, 1, 2, 3, 4, 5, 6, 7]
                .map(|k| Lanes::new(rows[0][k], rows[1][k], rows[2][k], rows[3][k]))
        }
    }
    #[inline(always)]
    fn scatter_rows<R: AsMut<[Real; 8]>>(columns: [Self; 4], rows: &mut [R], idx: &[u32; 4]) {
        // The 4x4 transpose again, then one store of four words per row.
        let [c0, c1, c2, c3] = columns;
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        {
            use std::arch::x86_64::{
                __m128, _mm_movehl_ps, _mm_movelh_ps, _mm_storeu_ps, _mm_unpackhi_ps,
                _mm_unpacklo_ps,
            };
            let [c0, c1, c2, c3] = [c0, c1, c2, c3].map(__m128::from);
            // SAFETY: SSE is part of x86-64; each store writes the first four of a row's
            // eight words, through an exclusive reference.
            unsafe {
                let (t0, t1) = (_mm_unpacklo_ps(c0, c1), _mm_unpacklo_ps(c2, c3));
                let (t2, t3) = (_mm_unpackhi_ps(c0, c1), _mm_unpackhi_ps(c2, c3));
                let out = [
                    _mm_movelh_ps(t0, t1),
                    _mm_movehl_ps(t1, t0),
                    _mm_movelh_ps(t2, t3),
                    _mm_movehl_ps(t3, t2),
                ];
                for (&i, row) in idx.iter().zip(out) {
                    _mm_storeu_ps(rows[i as usize].as_mut().as_mut_ptr(), row);
                }
            }
        }
        #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
        for (lane, &i) in idx.iter().enumerate() {
            let words = rows[i as usize].as_mut();
            for (word, column) in words.iter_mut().zip([c0, c1, c2, c3]) {
                *word = column[lane];
            }
        }
    }
}

/// Eight [`Real`]s side by side, 32-byte aligned.
///
/// On x86-64 (`f32`) one AVX register: each operation is one AVX instruction, so a `Lanes8`
/// may only be worked on where [`eight_lanes_available`] said yes (the wide solver builds
/// eight-lane bundles only then). Building one from numbers and reading its lanes back use no
/// AVX instruction and are safe anywhere. Elsewhere a plain array, worked lane by lane.
#[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct Lanes8(std::arch::x86_64::__m256);

/// Eight lane-wise truth values (all bits set for true), as AVX comparisons give them.
#[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct Mask8(std::arch::x86_64::__m256);

#[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
mod avx {
    //! `Lanes8` as AVX instructions. Every function here must run only on a processor with
    //! AVX2 (see [`Lanes8`]); they are inlined into the kernels compiled for it.
    use super::{Lanes8, Mask8, Wide};
    use crate::physics::math::Real;
    use std::arch::x86_64::*;
    use std::ops::{
        Add, AddAssign, BitAnd, BitOr, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign,
    };

    /// Lane-wise binary operator on `Lanes8` by one AVX instruction, and its assigning form.
    macro_rules! avx_op {
        ($trait:ident, $method:ident, $assign:ident, $assign_method:ident, $intrinsic:ident) => {
            impl $trait for Lanes8 {
                type Output = Lanes8;
                #[inline(always)]
                fn $method(self, rhs: Lanes8) -> Lanes8 {
                    // SAFETY: `Lanes8` is only worked on where AVX2 is available.
                    Lanes8(unsafe { $intrinsic(self.0, rhs.0) })
                }
            }
            impl $assign for Lanes8 {
                #[inline(always)]
                fn $assign_method(&mut self, rhs: Lanes8) {
                    *self = $trait::$method(*self, rhs);
                }
            }
        };
    }
    avx_op!(Add, add, AddAssign, add_assign, _mm256_add_ps);
    avx_op!(Sub, sub, SubAssign, sub_assign, _mm256_sub_ps);
    avx_op!(Mul, mul, MulAssign, mul_assign, _mm256_mul_ps);
    avx_op!(Div, div, DivAssign, div_assign, _mm256_div_ps);
    impl Neg for Lanes8 {
        type Output = Lanes8;
        /// Flip the sign bit, as glam does.
        #[inline(always)]
        fn neg(self) -> Lanes8 {
            // SAFETY: as above.
            Lanes8(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
        }
    }
    impl BitAnd for Mask8 {
        type Output = Mask8;
        #[inline(always)]
        fn bitand(self, rhs: Mask8) -> Mask8 {
            // SAFETY: as above.
            Mask8(unsafe { _mm256_and_ps(self.0, rhs.0) })
        }
    }
    impl BitOr for Mask8 {
        type Output = Mask8;
        #[inline(always)]
        fn bitor(self, rhs: Mask8) -> Mask8 {
            // SAFETY: as above.
            Mask8(unsafe { _mm256_or_ps(self.0, rhs.0) })
        }
    }

    impl Wide for Lanes8 {
        const WIDTH: usize = 8;
        // SAFETY (both): `__m256` is eight `f32`s, any bit pattern valid.
        const ZERO: Self = Lanes8(unsafe { std::mem::transmute::<[f32; 8], __m256>([0.0; 8]) });
        const ONE: Self = Lanes8(unsafe { std::mem::transmute::<[f32; 8], __m256>([1.0; 8]) });
        type Mask = Mask8;
        type Index = [u32; 8];
        type Array = [Real; 8];
        #[inline(always)]
        fn splat(x: Real) -> Self {
            Self::from_array([x; 8])
        }
        #[inline(always)]
        fn index_splat(i: u32) -> [u32; 8] {
            [i; 8]
        }
        #[inline(always)]
        fn set_lane(&mut self, i: usize, x: Real) {
            // SAFETY: `Lanes8` is a transparent `__m256`, which is eight `f32`s (and aligned
            // for them); no AVX instruction is involved.
            let lanes = unsafe { &mut *(self as *mut Lanes8).cast::<[f32; 8]>() };
            lanes[i] = x;
        }
        #[inline(always)]
        fn to_lanes(self) -> [Real; 8] {
            self.to_array()
        }
        #[inline(always)]
        fn max(self, rhs: Self) -> Self {
            // SAFETY: as above. `maxps` returns the second operand unless the first is greater.
            Lanes8(unsafe { _mm256_max_ps(self.0, rhs.0) })
        }
        #[inline(always)]
        fn min(self, rhs: Self) -> Self {
            // SAFETY: as above.
            Lanes8(unsafe { _mm256_min_ps(self.0, rhs.0) })
        }
        #[inline(always)]
        fn cmpgt(self, rhs: Self) -> Mask8 {
            // SAFETY: as above. Ordered and quiet, as SSE's `cmpltps` with swapped operands.
            Mask8(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, rhs.0) })
        }
        #[inline(always)]
        fn cmpge(self, rhs: Self) -> Mask8 {
            // SAFETY: as above.
            Mask8(unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(self.0, rhs.0) })
        }
        #[inline(always)]
        fn select(mask: Mask8, if_true: Self, if_false: Self) -> Self {
            // SAFETY: as above. Every mask lane is all ones or all zeros.
            Lanes8(unsafe { _mm256_blendv_ps(if_false.0, if_true.0, mask.0) })
        }
        #[inline(always)]
        fn any(mask: Mask8) -> bool {
            // SAFETY: as above.
            unsafe { _mm256_movemask_ps(mask.0) != 0 }
        }
        #[inline(always)]
        fn columns<'a>(row: impl Fn(usize) -> &'a [Real; 8]) -> [Self; 8] {
            // SAFETY: as above; each load reads one row's eight f32s.
            unsafe {
                let r0 = _mm256_loadu_ps(row(0).as_ptr());
                let r1 = _mm256_loadu_ps(row(1).as_ptr());
                let r2 = _mm256_loadu_ps(row(2).as_ptr());
                let r3 = _mm256_loadu_ps(row(3).as_ptr());
                let r4 = _mm256_loadu_ps(row(4).as_ptr());
                let r5 = _mm256_loadu_ps(row(5).as_ptr());
                let r6 = _mm256_loadu_ps(row(6).as_ptr());
                let r7 = _mm256_loadu_ps(row(7).as_ptr());
                // The 8x8 transpose. Rows interleaved in pairs (within each 128-bit half)...
                let (t0, t1) = (_mm256_unpacklo_ps(r0, r1), _mm256_unpackhi_ps(r0, r1));
                let (t2, t3) = (_mm256_unpacklo_ps(r2, r3), _mm256_unpackhi_ps(r2, r3));
                let (t4, t5) = (_mm256_unpacklo_ps(r4, r5), _mm256_unpackhi_ps(r4, r5));
                let (t6, t7) = (_mm256_unpacklo_ps(r6, r7), _mm256_unpackhi_ps(r6, r7));
                // ... then in fours: s_k holds field k of rows 0-3 (or 4-7 for s_(k+4)) in
                // its low half and field k + 4 in its high half ...
                let s0 = _mm256_shuffle_ps::<0x44>(t0, t2);
                let s1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
                let s2 = _mm256_shuffle_ps::<0x44>(t1, t3);
                let s3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
                let s4 = _mm256_shuffle_ps::<0x44>(t4, t6);
                let s5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
                let s6 = _mm256_shuffle_ps::<0x44>(t5, t7);
                let s7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
                // ... and the halves joined. (Spelled out: no closure may stand between the
                // AVX2 kernels and these instructions.)
                [
                    Lanes8(_mm256_permute2f128_ps::<0x20>(s0, s4)),
                    Lanes8(_mm256_permute2f128_ps::<0x20>(s1, s5)),
                    Lanes8(_mm256_permute2f128_ps::<0x20>(s2, s6)),
                    Lanes8(_mm256_permute2f128_ps::<0x20>(s3, s7)),
                    Lanes8(_mm256_permute2f128_ps::<0x31>(s0, s4)),
                    Lanes8(_mm256_permute2f128_ps::<0x31>(s1, s5)),
                    Lanes8(_mm256_permute2f128_ps::<0x31>(s2, s6)),
                    Lanes8(_mm256_permute2f128_ps::<0x31>(s3, s7)),
                ]
            }
        }
        #[inline(always)]
        fn scatter_rows<R: AsMut<[Real; 8]>>(columns: [Self; 4], rows: &mut [R], idx: &[u32; 8]) {
            let [c0, c1, c2, c3] = columns.map(|c| c.0);
            // SAFETY: as above; each store writes the first four of a row's eight f32s,
            // through an exclusive reference.
            unsafe {
                // The 8x4 transpose: lanes interleaved in pairs, then in fours; the low half
                // of v_k is lane k's four words and the high half lane k + 4's.
                let (u0, u1) = (_mm256_unpacklo_ps(c0, c1), _mm256_unpackhi_ps(c0, c1));
                let (u2, u3) = (_mm256_unpacklo_ps(c2, c3), _mm256_unpackhi_ps(c2, c3));
                let v0 = _mm256_shuffle_ps::<0x44>(u0, u2);
                let v1 = _mm256_shuffle_ps::<0xEE>(u0, u2);
                let v2 = _mm256_shuffle_ps::<0x44>(u1, u3);
                let v3 = _mm256_shuffle_ps::<0xEE>(u1, u3);
                let mut store = |lane: usize, words: __m128| {
                    _mm_storeu_ps(rows[idx[lane] as usize].as_mut().as_mut_ptr(), words)
                };
                store(0, _mm256_castps256_ps128(v0));
                store(1, _mm256_castps256_ps128(v1));
                store(2, _mm256_castps256_ps128(v2));
                store(3, _mm256_castps256_ps128(v3));
                store(4, _mm256_extractf128_ps::<1>(v0));
                store(5, _mm256_extractf128_ps::<1>(v1));
                store(6, _mm256_extractf128_ps::<1>(v2));
                store(7, _mm256_extractf128_ps::<1>(v3));
            }
        }
    }

    impl Lanes8 {
        /// Eight numbers as lanes (no AVX instruction: a plain copy).
        #[inline(always)]
        pub fn from_array(a: [Real; 8]) -> Lanes8 {
            // SAFETY: same size, any bit pattern valid.
            Lanes8(unsafe { std::mem::transmute::<[f32; 8], __m256>(a) })
        }
        /// The lanes as numbers (no AVX instruction).
        #[inline(always)]
        pub fn to_array(self) -> [Real; 8] {
            // SAFETY: as above.
            unsafe { std::mem::transmute::<__m256, [f32; 8]>(self.0) }
        }
    }
}

#[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
pub(crate) use portable::Lanes8;

#[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
mod portable {
    //! `Lanes8` as a plain array where there is no AVX: never chosen by the solver there
    //! ([`super::eight_lanes_available`] is false), kept so the kernels compile the same.
    use super::Wide;
    use crate::physics::math::Real;
    use std::ops::{
        Add, AddAssign, BitAnd, BitOr, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign,
    };

    /// Eight [`Real`]s side by side.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Lanes8([Real; 8]);

    /// Eight lane-wise truth values.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Mask8([bool; 8]);

    /// Lane-wise binary operator on `Lanes8`, and its assigning form.
    macro_rules! lanes8_op {
        ($trait:ident, $method:ident, $assign:ident, $assign_method:ident, $op:tt) => {
            impl $trait for Lanes8 {
                type Output = Lanes8;
                fn $method(self, rhs: Lanes8) -> Lanes8 {
                    Lanes8(std::array::from_fn(|i| self.0[i] $op rhs.0[i]))
                }
            }
            impl $assign for Lanes8 {
                fn $assign_method(&mut self, rhs: Lanes8) {
                    *self = *self $op rhs;
                }
            }
        };
    }
    lanes8_op!(Add, add, AddAssign, add_assign, +);
    lanes8_op!(Sub, sub, SubAssign, sub_assign, -);
    lanes8_op!(Mul, mul, MulAssign, mul_assign, *);
    lanes8_op!(Div, div, DivAssign, div_assign, /);
    impl Neg for Lanes8 {
        type Output = Lanes8;
        fn neg(self) -> Lanes8 {
            Lanes8(self.0.map(|x| -x))
        }
    }
    impl BitAnd for Mask8 {
        type Output = Mask8;
        fn bitand(self, rhs: Mask8) -> Mask8 {
            Mask8(std::array::from_fn(|i| self.0[i] & rhs.0[i]))
        }
    }
    impl BitOr for Mask8 {
        type Output = Mask8;
        fn bitor(self, rhs: Mask8) -> Mask8 {
            Mask8(std::array::from_fn(|i| self.0[i] | rhs.0[i]))
        }
    }

    impl Wide for Lanes8 {
        const WIDTH: usize = 8;
        const ZERO: Self = Lanes8([0.0; 8]);
        const ONE: Self = Lanes8([1.0; 8]);
        type Mask = Mask8;
        type Index = [u32; 8];
        type Array = [Real; 8];
        fn splat(x: Real) -> Self {
            Lanes8([x; 8])
        }
        fn index_splat(i: u32) -> [u32; 8] {
            [i; 8]
        }
        fn set_lane(&mut self, i: usize, x: Real) {
            self.0[i] = x;
        }
        fn to_lanes(self) -> [Real; 8] {
            self.0
        }
        fn max(self, rhs: Self) -> Self {
            Lanes8(std::array::from_fn(|i| {
                if self.0[i] > rhs.0[i] {
                    self.0[i]
                } else {
                    rhs.0[i]
                }
            }))
        }
        fn min(self, rhs: Self) -> Self {
            Lanes8(std::array::from_fn(|i| {
                if self.0[i] < rhs.0[i] {
                    self.0[i]
                } else {
                    rhs.0[i]
                }
            }))
        }
        fn cmpgt(self, rhs: Self) -> Mask8 {
            Mask8(std::array::from_fn(|i| self.0[i] > rhs.0[i]))
        }
        fn cmpge(self, rhs: Self) -> Mask8 {
            Mask8(std::array::from_fn(|i| self.0[i] >= rhs.0[i]))
        }
        fn select(mask: Mask8, if_true: Self, if_false: Self) -> Self {
            Lanes8(std::array::from_fn(|i| {
                if mask.0[i] {
                    if_true.0[i]
                } else {
                    if_false.0[i]
                }
            }))
        }
        fn any(mask: Mask8) -> bool {
            mask.0.iter().any(|&m| m)
        }
        #[inline(always)]
        fn columns<'a>(row: impl Fn(usize) -> &'a [Real; 8]) -> [Self; 8] {
            let rows = [0, 1, 2, 3, 4, 5, 6, 7].map(row);
            [0, 1, 2, 3, 4, 5, 6, 7].map(|k| Lanes8(rows.map(|r| r[k])))
        }
        fn scatter_rows<R: AsMut<[Real; 8]>>(columns: [Self; 4], rows: &mut [R], idx: &[u32; 8]) {
            for (lane, &i) in idx.iter().enumerate() {
                let words = rows[i as usize].as_mut();
                for (word, column) in words.iter_mut().zip(&columns) {
                    *word = column.0[lane];
                }
            }
        }
    }
}

/// Whether this machine runs the eight-lane kernels compiled for AVX2. Not in `f64` builds:
/// there glam's four lanes are scalar code whose `max` is Rust's, not SSE's, so the two widths
/// could differ in the sign of a zero.
pub(crate) fn eight_lanes_available() -> bool {
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
    {
        false
    }
}

/// Ask the processor to start loading every cache line of `x` into the cache (a hint:
/// nothing is read, and results do not change). For passes that visit scattered values in an
/// order known ahead: the load of the next values overlaps the work on these.
#[inline(always)]
pub(crate) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let start = (x as *const T).cast::<i8>();
        for offset in (0..std::mem::size_of::<T>()).step_by(64) {
            // SAFETY: SSE is part of x86-64, and a prefetch neither reads memory nor faults;
            // the address stays within `x`.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.add(offset)) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod tests {
    use super::*;

    /// The eight-lane operations agree bit for bit with glam's four lanes, signs of zero
    /// included (the property the World's determinism across widths rests on).
    #[test]
    fn eight_lanes_match_glam_lane_by_lane() {
        if !eight_lanes_available() {
            eprintln!("no AVX2 here: the eight-lane kernels never run on this machine");
            return;
        }
        let values: [Real; 8] = [0.0, -0.0, 1.5, -2.25, 1e-30, -7.0, 3.0, 1.5];
        let other: [Real; 8] = [-0.0, 0.0, 1.5, 4.0, -1e-30, -7.5, -3.0, 2.0];
        let a8 = Lanes8::from_array(values);
        let b8 = Lanes8::from_array(other);
        let nine = Lanes8::splat(9.0);
        let eights: [Lanes8; 8] = [
            a8 + b8,
            a8 - b8,
            a8 * b8,
            a8 / (b8 + nine),
            -a8,
            Wide::max(a8, b8),
            Wide::min(a8, b8),
            Wide::select(Wide::cmpge(a8, b8), a8, -b8),
        ];
        for half in 0..2 {
            let r = half * 4..half * 4 + 4;
            let a4 = Lanes::from_slice(&values[r.clone()]);
            let b4 = Lanes::from_slice(&other[r]);
            let fours: [Lanes; 8] = [
                a4 + b4,
                a4 - b4,
                a4 * b4,
                a4 / (b4 + Lanes::splat(9.0)),
                -a4,
                Wide::max(a4, b4),
                Wide::min(a4, b4),
                Wide::select(Wide::cmpge(a4, b4), a4, -b4),
            ];
            for (k, (four, eight)) in fours.iter().zip(&eights).enumerate() {
                for i in 0..4 {
                    assert_eq!(
                        four[i].to_bits(),
                        eight.to_array()[half * 4 + i].to_bits(),
                        "operation {k}, lane {}",
                        half * 4 + i
                    );
                }
            }
        }
        assert!(Lanes8::any(a8.cmpgt(b8)));
        assert!(!Lanes8::any(a8.cmpgt(Lanes8::splat(10.0))));
    }

    /// `columns` is a transpose at both widths: lane i of column k is row i's word k (rows
    /// numbered 10 i + k, so a swapped or misplaced word shows); `scatter_rows` puts the
    /// first four columns back, in rows named by the lanes' indices, and nothing else.
    #[test]
    fn columns_and_scatter_rows_transpose_the_rows() {
        let rows: [[Real; 8]; 8] =
            std::array::from_fn(|i| std::array::from_fn(|k| (10 * i + k) as Real));
        // Lane i writes row 7 - i, so a scatter that ignored the indices shows too.
        struct Row([Real; 8]);
        impl AsMut<[Real; 8]> for Row {
            fn as_mut(&mut self) -> &mut [Real; 8] {
                &mut self.0
            }
        }
        let blank = || [0; 8].map(|_| Row([-1.0; 8]));
        let expected = |written: &[Row; 8], width: usize| {
            for (r, row) in written.iter().enumerate() {
                let lane = 7 - r;
                for (k, &word) in row.0.iter().enumerate() {
                    let want = if lane < width && k < 4 {
                        rows[lane][k]
                    } else {
                        -1.0
                    };
                    assert_eq!(word, want, "row {r} word {k} at width {width}");
                }
            }
        };
        let four = Lanes::columns(|i| &rows[i]);
        for (k, column) in four.iter().enumerate() {
            assert_eq!(
                column.to_lanes(),
                std::array::from_fn(|i| rows[i][k]),
                "column {k}"
            );
        }
        let mut written = blank();
        Lanes::scatter_rows(
            [four[0], four[1], four[2], four[3]],
            &mut written,
            &[7, 6, 5, 4],
        );
        expected(&written, 4);
        if !eight_lanes_available() {
            eprintln!("no AVX2 here: the eight-lane transpose never runs on this machine");
            return;
        }
        let eight = Lanes8::columns(|i| &rows[i]);
        for (k, column) in eight.iter().enumerate() {
            assert_eq!(
                column.to_lanes(),
                std::array::from_fn(|i| rows[i][k]),
                "column {k}"
            );
        }
        let mut written = blank();
        let idx = [7, 6, 5, 4, 3, 2, 1, 0];
        Lanes8::scatter_rows([eight[0], eight[1], eight[2], eight[3]], &mut written, &idx);
        expected(&written, 8);
    }
}
