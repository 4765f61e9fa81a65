//! [`Lanes1`]: one [`Real`] as a lane type, so that the contacts the colouring could not place
//! (the overflow) run through the same kernels as the bundles, at width one.

use super::Wide;
use crate::physics::math::Real;
use std::ops::{
    Add, AddAssign, BitAnd, BitOr, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign,
};

/// One [`Real`] in a lane.
#[derive(Clone, Copy, Debug, Default)]
#[repr(transparent)]
pub(crate) struct Lanes1(pub Real);

/// `Lanes1`'s arithmetic: the same IEEE operation on its one number.
macro_rules! scalar_op {
    ($trait:ident, $method:ident, $assign:ident, $assign_method:ident, $op:tt) => {
        impl $trait for Lanes1 {
            type Output = Lanes1;
            #[inline(always)]
            fn $method(self, rhs: Lanes1) -> Lanes1 {
                Lanes1(self.0 $op rhs.0)
            }
        }
        impl $assign for Lanes1 {
            #[inline(always)]
            fn $assign_method(&mut self, rhs: Lanes1) {
                self.0 = self.0 $op rhs.0;
            }
        }
    };
}
scalar_op!(Add, add, AddAssign, add_assign, +);
scalar_op!(Sub, sub, SubAssign, sub_assign, -);
scalar_op!(Mul, mul, MulAssign, mul_assign, *);
scalar_op!(Div, div, DivAssign, div_assign, /);

impl Neg for Lanes1 {
    type Output = Lanes1;
    #[inline(always)]
    fn neg(self) -> Lanes1 {
        Lanes1(-self.0)
    }
}

/// A lane's truth value.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mask1(bool);

impl BitAnd for Mask1 {
    type Output = Mask1;
    #[inline(always)]
    fn bitand(self, rhs: Mask1) -> Mask1 {
        Mask1(self.0 & rhs.0)
    }
}

impl BitOr for Mask1 {
    type Output = Mask1;
    #[inline(always)]
    fn bitor(self, rhs: Mask1) -> Mask1 {
        Mask1(self.0 | rhs.0)
    }
}

impl Wide for Lanes1 {
    const WIDTH: usize = 1;
    const ZERO: Self = Lanes1(0.0);
    const ONE: Self = Lanes1(1.0);
    type Mask = Mask1;
    type Index = [u32; 1];
    type Array = [Real; 1];
    #[inline(always)]
    fn splat(x: Real) -> Self {
        Lanes1(x)
    }
    #[inline(always)]
    fn index_splat(i: u32) -> [u32; 1] {
        [i]
    }
    #[inline(always)]
    fn set_lane(&mut self, _: usize, x: Real) {
        self.0 = x;
    }
    #[inline(always)]
    fn lane(&self, _: usize) -> Real {
        self.0
    }
    #[inline(always)]
    fn to_lanes(self) -> [Real; 1] {
        [self.0]
    }
    #[inline(always)]
    fn max(self, rhs: Self) -> Self {
        // SSE's rule: the second operand unless the first is greater.
        if self.0 > rhs.0 {
            self
        } else {
            rhs
        }
    }
    #[inline(always)]
    fn min(self, rhs: Self) -> Self {
        if self.0 < rhs.0 {
            self
        } else {
            rhs
        }
    }
    #[inline(always)]
    fn cmpgt(self, rhs: Self) -> Mask1 {
        Mask1(self.0 > rhs.0)
    }
    #[inline(always)]
    fn cmpge(self, rhs: Self) -> Mask1 {
        Mask1(self.0 >= rhs.0)
    }
    #[inline(always)]
    fn select(mask: Mask1, if_true: Self, if_false: Self) -> Self {
        if mask.0 {
            if_true
        } else {
            if_false
        }
    }
    #[inline(always)]
    fn any(mask: Mask1) -> bool {
        mask.0
    }
    #[inline(always)]
    fn columns<'a>(row: impl Fn(usize) -> &'a [Real; 8]) -> [Self; 8] {
        row(0).map(Lanes1)
    }
    #[inline(always)]
    fn scatter_rows<R: AsMut<[Real; 8]>>(columns: [Self; 4], rows: &mut [R], idx: &[u32; 1]) {
        let words = rows[idx[0] as usize].as_mut();
        for (word, column) in words.iter_mut().zip(columns) {
            *word = column.0;
        }
    }
}
