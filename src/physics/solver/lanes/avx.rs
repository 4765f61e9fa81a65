//! [`Lanes8`] on x86-64 (`f32`): one AVX register, each operation one AVX instruction. Every
//! function here must run only on a processor with AVX2 (see [`super::eight_lanes_available`]);
//! they are inlined into the kernels compiled for it.

use super::Wide;
use crate::physics::math::Real;
use crate::physics::solver::BodyRows;
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
    fn lane(&self, i: usize) -> Real {
        // SAFETY: as in `set_lane`.
        let lanes = unsafe { &*(self as *const Lanes8).cast::<[f32; 8]>() };
        lanes[i]
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
        let words = rows_of_columns(columns);
        for (lane, words) in words.into_iter().enumerate() {
            // SAFETY: AVX2 is available (as above); the store writes the first four of a row's
            // eight f32s, through an exclusive reference.
            unsafe { _mm_storeu_ps(rows[idx[lane] as usize].as_mut().as_mut_ptr(), words) }
        }
    }
    /// As [`Wide::scatter_rows`], a row a store, but for the skipped lanes. (The lane-by-lane
    /// default wrote each row in four pieces, which the next gather of the row read in one,
    /// past the store buffer's forwarding.)
    #[inline(always)]
    fn scatter_rows_shared(columns: [Self; 4], rows: BodyRows, idx: &[u32; 8], skip: u8) {
        let words = rows_of_columns(columns);
        for (lane, words) in words.into_iter().enumerate() {
            if skip >> lane & 1 == 0 {
                // SAFETY: AVX2 is available (as above); `words` gives the row's first four of
                // eight f32s, in bounds.
                unsafe { _mm_storeu_ps(rows.words(idx[lane]), words) }
            }
        }
    }
}

/// The inverse of [`Wide::columns`] for four columns: each lane's four words, lane by lane.
#[inline(always)]
fn rows_of_columns(columns: [Lanes8; 4]) -> [__m128; 8] {
    let [c0, c1, c2, c3] = columns.map(|c| c.0);
    // SAFETY: `Lanes8` is only worked on where AVX2 is available.
    unsafe {
        // The 8x4 transpose: lanes interleaved in pairs, then in fours; the low half of v_k is
        // lane k's four words and the high half lane k + 4's.
        let (u0, u1) = (_mm256_unpacklo_ps(c0, c1), _mm256_unpackhi_ps(c0, c1));
        let (u2, u3) = (_mm256_unpacklo_ps(c2, c3), _mm256_unpackhi_ps(c2, c3));
        let v0 = _mm256_shuffle_ps::<0x44>(u0, u2);
        let v1 = _mm256_shuffle_ps::<0xEE>(u0, u2);
        let v2 = _mm256_shuffle_ps::<0x44>(u1, u3);
        let v3 = _mm256_shuffle_ps::<0xEE>(u1, u3);
        [
            _mm256_castps256_ps128(v0),
            _mm256_castps256_ps128(v1),
            _mm256_castps256_ps128(v2),
            _mm256_castps256_ps128(v3),
            _mm256_extractf128_ps::<1>(v0),
            _mm256_extractf128_ps::<1>(v1),
            _mm256_extractf128_ps::<1>(v2),
            _mm256_extractf128_ps::<1>(v3),
        ]
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

/// Eight [`Real`]s side by side in one AVX register, 32-byte aligned: each operation is one
/// AVX instruction, so a `Lanes8` may only be worked on where
/// [`super::eight_lanes_available`] said yes (the solver packs eight-lane bundles only then).
/// Building one from numbers and reading its lanes back use no AVX instruction and are safe
/// anywhere.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct Lanes8(std::arch::x86_64::__m256);

/// Eight lane-wise truth values (all bits set for true), as AVX comparisons give them.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct Mask8(std::arch::x86_64::__m256);
