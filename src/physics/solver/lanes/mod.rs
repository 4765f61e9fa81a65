//! The soft step's lanes: one, four or eight [`Real`]s worked on side by side.
//!
//! [`Wide`] is what the contact kernels (`contact_solver.rs`) ask of a lane type. Three types
//! provide it: [`Lanes1`] (one number: the overflow contacts, which the colouring could not
//! place), [`Lanes4`] (glam's four-wide vector, SSE2 on x86-64) and [`Lanes8`] (an AVX
//! register, `avx.rs`, where the processor has AVX2; two `Lanes4` elsewhere, `pair.rs`, where
//! it is never chosen but keeps the kernels compiling the same). Every operation is the same
//! IEEE operation lane by lane in all three, and `max`/`min` follow SSE's rule (the second
//! operand unless the first is strictly greater, resp. smaller), so a contact's arithmetic,
//! and the World's result, does not depend on how many contacts share a bundle.

use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, Neg, Sub, SubAssign};

use super::BodyRows;
use crate::physics::math::Real;

#[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
mod avx;
#[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
pub(crate) use avx::Lanes8;
#[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
mod pair;
#[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
pub(crate) use pair::Lanes8;
mod scalar;
pub(crate) use scalar::Lanes1;

/// Four [`Real`]s side by side: glam's four-wide vector (SSE2 on x86-64).
#[cfg(not(feature = "f64"))]
pub(crate) type Lanes4 = glam::Vec4;
/// Four [`Real`]s side by side: glam's four-wide vector.
#[cfg(feature = "f64")]
pub(crate) type Lanes4 = glam::DVec4;

/// A lane type for the wide kernels: `WIDTH` independent [`Real`]s.
pub(crate) trait Wide:
    Copy
    + Send
    + Sync
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
    type Index: Copy + Send + Sync + std::fmt::Debug + AsRef<[u32]> + AsMut<[u32]>;
    /// The lanes as plain numbers.
    type Array: Copy + AsRef<[Real]>;
    /// Every lane `x`.
    fn splat(x: Real) -> Self;
    /// Every index lane `i`.
    fn index_splat(i: u32) -> Self::Index;
    /// Set lane `i` to `x`, in place (packing writes each lane once, where it lives).
    fn set_lane(&mut self, i: usize, x: Real);
    /// Lane `i`, read where it lives (the store reads one lane of a bundle at a time).
    fn lane(&self, i: usize) -> Real;
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

    /// [`Wide::scatter_rows`] into rows other workers share (`BodyRows`), but for the lanes
    /// whose bit is set in `skip` (bit i for lane i: a fixed body's), which write nothing.
    /// Lane by lane: the parallel step's kernels only.
    #[inline(always)]
    fn scatter_rows_shared(columns: [Self; 4], rows: BodyRows, idx: &Self::Index, skip: u8) {
        let columns = columns.map(Self::to_lanes);
        for (lane, &i) in idx.as_ref().iter().enumerate() {
            if skip >> lane & 1 == 0 {
                let words = rows.words(i);
                for (k, column) in columns.iter().enumerate() {
                    // SAFETY: the first four of the row's eight words, in bounds (`words`).
                    unsafe { *words.add(k) = column.as_ref()[lane] };
                }
            }
        }
    }

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
                Lanes4::$name(self, rhs)
            }
        )*
    };
}

impl Wide for Lanes4 {
    const WIDTH: usize = 4;
    const ZERO: Self = Lanes4::ZERO;
    const ONE: Self = Lanes4::ONE;
    type Mask = LanesMask;
    type Index = [u32; 4];
    type Array = [Real; 4];
    #[inline(always)]
    fn splat(x: Real) -> Self {
        Lanes4::splat(x)
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
    fn lane(&self, i: usize) -> Real {
        self[i]
    }
    #[inline(always)]
    fn to_lanes(self) -> [Real; 4] {
        self.to_array()
    }
    forward_to_glam!(cmpgt -> LanesMask, cmpge -> LanesMask);
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    forward_to_glam!(max -> Self, min -> Self);
    // Elsewhere glam's `max` is the target's (NEON's, or Rust's `f64::max`), which may differ
    // from SSE's rule in the sign of a zero: spelled out as SSE defines it.
    #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
    #[inline(always)]
    fn max(self, rhs: Self) -> Self {
        Lanes4::select(self.cmpgt(rhs), self, rhs)
    }
    #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
    #[inline(always)]
    fn min(self, rhs: Self) -> Self {
        Lanes4::select(rhs.cmpgt(self), self, rhs)
    }
    #[inline(always)]
    fn select(mask: LanesMask, if_true: Self, if_false: Self) -> Self {
        Lanes4::select(mask, if_true, if_false)
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
                    Lanes4::from(columns[0]),
                    Lanes4::from(columns[1]),
                    Lanes4::from(columns[2]),
                    Lanes4::from(columns[3]),
                    Lanes4::from(columns[4]),
                    Lanes4::from(columns[5]),
                    Lanes4::from(columns[6]),
                    Lanes4::from(columns[7]),
                ]
            }
        }
        #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
        {
            let rows = [row(0), row(1), row(2), row(3)];
            [0, 1, 2, 3, 4, 5, 6, 7]
                .map(|k| Lanes4::new(rows[0][k], rows[1][k], rows[2][k], rows[3][k]))
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

/// Whether this machine runs the eight-lane kernels compiled for AVX2: on x86-64 with AVX2, in
/// `f32` builds (the AVX `Lanes8` holds eight `f32`; an `f64` build runs four lanes).
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

/// The cache line's size on the processors we tune for (bytes).
#[cfg(target_arch = "x86_64")]
const CACHE_LINE: usize = 64;

/// Ask the processor to start loading every cache line of `x` into the cache (a hint:
/// nothing is read, and results do not change). For passes that visit scattered values in an
/// order known ahead: the load of the next values overlaps the work on these.
#[inline(always)]
pub(crate) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // From the start of the line `x` begins in: `x` need not start a line, and its last
        // bytes may lie in one more line than its size suggests.
        let start = (x as *const T).cast::<i8>();
        let skew = start as usize % CACHE_LINE;
        let first = start.wrapping_sub(skew);
        for offset in (0..skew + std::mem::size_of::<T>()).step_by(CACHE_LINE) {
            // SAFETY: SSE is part of x86-64, and a prefetch neither reads memory nor faults
            // (its address is a hint, here within the lines `x` spans).
            unsafe { _mm_prefetch::<_MM_HINT_T0>(first.wrapping_add(offset)) }
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
            let a4 = Lanes4::from_slice(&values[r.clone()]);
            let b4 = Lanes4::from_slice(&other[r]);
            let fours: [Lanes4; 8] = [
                a4 + b4,
                a4 - b4,
                a4 * b4,
                a4 / (b4 + Lanes4::splat(9.0)),
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
        let four = Lanes4::columns(|i| &rows[i]);
        for (k, column) in four.iter().enumerate() {
            assert_eq!(
                column.to_lanes(),
                std::array::from_fn(|i| rows[i][k]),
                "column {k}"
            );
        }
        let mut written = blank();
        Lanes4::scatter_rows(
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

    /// `scatter_rows_shared` writes what `scatter_rows` writes, but nothing for the lanes it
    /// is told to skip (a fixed body's, which bundles solved at once may share).
    #[test]
    fn a_shared_scatter_skips_the_fixed_lanes() {
        use crate::physics::solver::SolverBody;
        let rows: [[Real; 8]; 4] =
            std::array::from_fn(|i| std::array::from_fn(|k| (10 * i + k) as Real));
        let four = Lanes4::columns(|i| &rows[i]);
        let columns = [four[0], four[1], four[2], four[3]];
        let mut plain = [SolverBody::FIXED; 4];
        *plain[1].as_mut() = [-1.0; 8];
        let mut shared = plain;
        Lanes4::scatter_rows(columns, &mut plain, &[3, 2, 1, 0]);
        // Lane 2 (row 1) is skipped.
        Lanes4::scatter_rows_shared(columns, BodyRows::new(&mut shared), &[3, 2, 1, 0], 1 << 2);
        for (r, (p, s)) in plain.iter().zip(&shared).enumerate() {
            if r == 1 {
                assert_eq!(s.state(), &[-1.0; 8], "the skipped row is untouched");
                assert_eq!(&p.state()[..4], &rows[2][..4], "the plain scatter wrote it");
            } else {
                assert_eq!(p.state(), s.state(), "row {r}");
            }
        }
    }
}
