//! [`Lanes8`] where there is no AVX (other processors, or `f64` builds): two [`Lanes4`] side
//! by side. The solver never packs eight-lane bundles there ([`super::eight_lanes_available`]
//! is false); this keeps the kernels compiling the same on every target.

use super::{Lanes4, Wide};
use crate::physics::math::Real;
use std::ops::{
    Add, AddAssign, BitAnd, BitOr, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign,
};

/// Eight [`Real`]s as two halves of four.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lanes8([Lanes4; 2]);

/// Eight lane-wise truth values, as two halves.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mask8([<Lanes4 as Wide>::Mask; 2]);

/// A binary operator on both halves, and its assigning form.
macro_rules! halves_op {
    ($trait:ident, $method:ident, $assign:ident, $assign_method:ident) => {
        impl $trait for Lanes8 {
            type Output = Lanes8;
            fn $method(self, rhs: Lanes8) -> Lanes8 {
                Lanes8([
                    $trait::$method(self.0[0], rhs.0[0]),
                    $trait::$method(self.0[1], rhs.0[1]),
                ])
            }
        }
        impl $assign for Lanes8 {
            fn $assign_method(&mut self, rhs: Lanes8) {
                *self = $trait::$method(*self, rhs);
            }
        }
    };
}
halves_op!(Add, add, AddAssign, add_assign);
halves_op!(Sub, sub, SubAssign, sub_assign);
halves_op!(Mul, mul, MulAssign, mul_assign);
halves_op!(Div, div, DivAssign, div_assign);

impl Neg for Lanes8 {
    type Output = Lanes8;
    fn neg(self) -> Lanes8 {
        Lanes8([-self.0[0], -self.0[1]])
    }
}

impl BitAnd for Mask8 {
    type Output = Mask8;
    fn bitand(self, rhs: Mask8) -> Mask8 {
        Mask8([self.0[0] & rhs.0[0], self.0[1] & rhs.0[1]])
    }
}

impl BitOr for Mask8 {
    type Output = Mask8;
    fn bitor(self, rhs: Mask8) -> Mask8 {
        Mask8([self.0[0] | rhs.0[0], self.0[1] | rhs.0[1]])
    }
}

impl Wide for Lanes8 {
    const WIDTH: usize = 8;
    const ZERO: Self = Lanes8([Lanes4::ZERO; 2]);
    const ONE: Self = Lanes8([Lanes4::ONE; 2]);
    type Mask = Mask8;
    type Index = [u32; 8];
    type Array = [Real; 8];
    fn splat(x: Real) -> Self {
        Lanes8([Lanes4::splat(x); 2])
    }
    fn index_splat(i: u32) -> [u32; 8] {
        [i; 8]
    }
    fn set_lane(&mut self, i: usize, x: Real) {
        self.0[i / 4].set_lane(i % 4, x);
    }
    fn lane(&self, i: usize) -> Real {
        self.0[i / 4].lane(i % 4)
    }
    fn to_lanes(self) -> [Real; 8] {
        let (lo, hi) = (self.0[0].to_lanes(), self.0[1].to_lanes());
        std::array::from_fn(|i| if i < 4 { lo[i] } else { hi[i - 4] })
    }
    fn max(self, rhs: Self) -> Self {
        Lanes8([self.0[0].max(rhs.0[0]), self.0[1].max(rhs.0[1])])
    }
    fn min(self, rhs: Self) -> Self {
        Lanes8([self.0[0].min(rhs.0[0]), self.0[1].min(rhs.0[1])])
    }
    fn cmpgt(self, rhs: Self) -> Mask8 {
        Mask8([self.0[0].cmpgt(rhs.0[0]), self.0[1].cmpgt(rhs.0[1])])
    }
    fn cmpge(self, rhs: Self) -> Mask8 {
        Mask8([self.0[0].cmpge(rhs.0[0]), self.0[1].cmpge(rhs.0[1])])
    }
    fn select(mask: Mask8, if_true: Self, if_false: Self) -> Self {
        Lanes8([
            Lanes4::select(mask.0[0], if_true.0[0], if_false.0[0]),
            Lanes4::select(mask.0[1], if_true.0[1], if_false.0[1]),
        ])
    }
    fn any(mask: Mask8) -> bool {
        Lanes4::any(mask.0[0]) || Lanes4::any(mask.0[1])
    }
    fn columns<'a>(row: impl Fn(usize) -> &'a [Real; 8]) -> [Self; 8] {
        let lo = Lanes4::columns(&row);
        let hi = Lanes4::columns(|i| row(i + 4));
        std::array::from_fn(|k| Lanes8([lo[k], hi[k]]))
    }
    fn scatter_rows<R: AsMut<[Real; 8]>>(columns: [Self; 4], rows: &mut [R], idx: &[u32; 8]) {
        let lo = columns.map(|c| c.0[0]);
        let hi = columns.map(|c| c.0[1]);
        Lanes4::scatter_rows(lo, rows, &[idx[0], idx[1], idx[2], idx[3]]);
        Lanes4::scatter_rows(hi, rows, &[idx[4], idx[5], idx[6], idx[7]]);
    }
}
