//! Scalars for generic geometry code: [`Real`] over `f64` and forward-mode
//! duals, [`Dual1`] (value, gradient) and [`Dual2`] (value, gradient, exact Hessian).
//! Convention: variable `i` of an `N`-dual has gradient `e_i`; all storage is fixed-size.

use nalgebra::{SMatrix, SVector};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A scalar that generic distance code runs on: `f64` for values, duals for
/// derivatives. Arithmetic with itself and with `f64` constants.
pub trait Real:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + AddAssign
    + SubAssign
{
    /// A constant (zero derivatives).
    fn cst(x: f64) -> Self;
    /// Independent variable number `i` with value `x` (a plain value for `f64`).
    fn var(x: f64, i: usize) -> Self;
    /// The value, without derivatives.
    fn val(&self) -> f64;
    /// Square root (the argument must be positive where derivatives are wanted).
    fn sqrt(self) -> Self;
    /// Natural logarithm.
    fn ln(self) -> Self;
    /// Reciprocal 1/x.
    fn recip(self) -> Self;
    /// The square x*x.
    fn sq(self) -> Self {
        self * self
    }
    /// `f(self)` for a scalar function given its value `f`, first and
    /// second derivatives `df`, `ddf` at `self`'s value: one chain rule
    /// in place of the operations that would compute `f`.
    fn map(self, f: f64, df: f64, ddf: f64) -> Self;
}

impl Real for f64 {
    fn cst(x: f64) -> Self {
        x
    }
    fn var(x: f64, _i: usize) -> Self {
        x
    }
    fn val(&self) -> f64 {
        *self
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn ln(self) -> Self {
        f64::ln(self)
    }
    fn recip(self) -> Self {
        f64::recip(self)
    }
    fn map(self, f: f64, _df: f64, _ddf: f64) -> Self {
        f
    }
}

/// First-order forward dual: value `v` and gradient `g` with respect to `N` variables.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual1<const N: usize> {
    /// Value.
    pub v: f64,
    /// Gradient.
    pub g: SVector<f64, N>,
}

impl<const N: usize> Dual1<N> {
    /// Variable `i` (gradient `e_i`) with value `v`.
    pub fn var(v: f64, i: usize) -> Self {
        assert!(i < N, "variable index {i} out of 0..{N}");
        let mut g = SVector::zeros();
        g[i] = 1.0;
        Dual1 { v, g }
    }
    /// A constant.
    pub fn cst(v: f64) -> Self {
        Dual1 {
            v,
            g: SVector::zeros(),
        }
    }
    /// The chain rule for f(self) given f and f' at the value.
    fn chain(self, f: f64, df: f64) -> Self {
        Dual1 {
            v: f,
            g: self.g * df,
        }
    }
}

impl<const N: usize> Add for Dual1<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Dual1 {
            v: self.v + o.v,
            g: self.g + o.g,
        }
    }
}
impl<const N: usize> Sub for Dual1<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Dual1 {
            v: self.v - o.v,
            g: self.g - o.g,
        }
    }
}
impl<const N: usize> Mul for Dual1<N> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Dual1 {
            v: self.v * o.v,
            g: self.g * o.v + o.g * self.v,
        }
    }
}
impl<const N: usize> Div for Dual1<N> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let q = self.v / o.v;
        Dual1 {
            v: q,
            g: (self.g - o.g * q) / o.v,
        }
    }
}
impl<const N: usize> Neg for Dual1<N> {
    type Output = Self;
    fn neg(self) -> Self {
        Dual1 {
            v: -self.v,
            g: -self.g,
        }
    }
}
impl<const N: usize> Add<f64> for Dual1<N> {
    type Output = Self;
    fn add(self, c: f64) -> Self {
        Dual1 {
            v: self.v + c,
            g: self.g,
        }
    }
}
impl<const N: usize> Sub<f64> for Dual1<N> {
    type Output = Self;
    fn sub(self, c: f64) -> Self {
        Dual1 {
            v: self.v - c,
            g: self.g,
        }
    }
}
impl<const N: usize> Mul<f64> for Dual1<N> {
    type Output = Self;
    fn mul(self, c: f64) -> Self {
        Dual1 {
            v: self.v * c,
            g: self.g * c,
        }
    }
}
impl<const N: usize> Div<f64> for Dual1<N> {
    type Output = Self;
    fn div(self, c: f64) -> Self {
        Dual1 {
            v: self.v / c,
            g: self.g / c,
        }
    }
}
impl<const N: usize> AddAssign for Dual1<N> {
    fn add_assign(&mut self, o: Self) {
        self.v += o.v;
        self.g += o.g;
    }
}
impl<const N: usize> SubAssign for Dual1<N> {
    fn sub_assign(&mut self, o: Self) {
        self.v -= o.v;
        self.g -= o.g;
    }
}

impl<const N: usize> Real for Dual1<N> {
    fn map(self, f: f64, df: f64, _ddf: f64) -> Self {
        self.chain(f, df)
    }
    fn cst(x: f64) -> Self {
        Dual1::cst(x)
    }
    fn var(x: f64, i: usize) -> Self {
        Dual1::var(x, i)
    }
    fn val(&self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        self.chain(r, 0.5 / r)
    }
    fn ln(self) -> Self {
        self.chain(self.v.ln(), 1.0 / self.v)
    }
    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r)
    }
}

/// Second-order forward dual: value `v`, gradient `g` and Hessian `h` (symmetric)
/// with respect to `N` variables; exact second derivatives, no heap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual2<const N: usize> {
    /// Value.
    pub v: f64,
    /// Gradient.
    pub g: SVector<f64, N>,
    /// Hessian.
    pub h: SMatrix<f64, N, N>,
}

impl<const N: usize> Dual2<N> {
    /// Variable `i` (gradient `e_i`, zero Hessian) with value `v`.
    pub fn var(v: f64, i: usize) -> Self {
        assert!(i < N, "variable index {i} out of 0..{N}");
        let mut g = SVector::zeros();
        g[i] = 1.0;
        Dual2 {
            v,
            g,
            h: SMatrix::zeros(),
        }
    }
    /// A constant.
    pub fn cst(v: f64) -> Self {
        Dual2 {
            v,
            g: SVector::zeros(),
            h: SMatrix::zeros(),
        }
    }
    /// The chain rule for f(self) given f, f' and f'' at the value:
    /// g = f' g, h = f' h + f'' g g^T.
    fn chain(self, f: f64, df: f64, ddf: f64) -> Self {
        let mut h = self.h * df;
        h.ger(ddf, &self.g, &self.g, 1.0);
        Dual2 {
            v: f,
            g: self.g * df,
            h,
        }
    }
}

impl<const N: usize> Add for Dual2<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Dual2 {
            v: self.v + o.v,
            g: self.g + o.g,
            h: self.h + o.h,
        }
    }
}
impl<const N: usize> Sub for Dual2<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Dual2 {
            v: self.v - o.v,
            g: self.g - o.g,
            h: self.h - o.h,
        }
    }
}
impl<const N: usize> Mul for Dual2<N> {
    type Output = Self;
    /// Product rule: h = a.v b.h + b.v a.h + a.g b.g^T + b.g a.g^T.
    fn mul(self, o: Self) -> Self {
        let mut h = self.h * o.v;
        h += o.h * self.v;
        h.ger(1.0, &self.g, &o.g, 1.0);
        h.ger(1.0, &o.g, &self.g, 1.0);
        Dual2 {
            v: self.v * o.v,
            g: self.g * o.v + o.g * self.v,
            h,
        }
    }
}
impl<const N: usize> Div for Dual2<N> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let q = self * o.recip();
        // The value as f64 division gives it, bit for bit.
        Dual2 {
            v: self.v / o.v,
            ..q
        }
    }
}
impl<const N: usize> Neg for Dual2<N> {
    type Output = Self;
    fn neg(self) -> Self {
        Dual2 {
            v: -self.v,
            g: -self.g,
            h: -self.h,
        }
    }
}
impl<const N: usize> Add<f64> for Dual2<N> {
    type Output = Self;
    fn add(self, c: f64) -> Self {
        Dual2 {
            v: self.v + c,
            ..self
        }
    }
}
impl<const N: usize> Sub<f64> for Dual2<N> {
    type Output = Self;
    fn sub(self, c: f64) -> Self {
        Dual2 {
            v: self.v - c,
            ..self
        }
    }
}
impl<const N: usize> Mul<f64> for Dual2<N> {
    type Output = Self;
    fn mul(self, c: f64) -> Self {
        Dual2 {
            v: self.v * c,
            g: self.g * c,
            h: self.h * c,
        }
    }
}
impl<const N: usize> Div<f64> for Dual2<N> {
    type Output = Self;
    fn div(self, c: f64) -> Self {
        Dual2 {
            v: self.v / c,
            g: self.g / c,
            h: self.h / c,
        }
    }
}
impl<const N: usize> AddAssign for Dual2<N> {
    fn add_assign(&mut self, o: Self) {
        self.v += o.v;
        self.g += o.g;
        self.h += o.h;
    }
}
impl<const N: usize> SubAssign for Dual2<N> {
    fn sub_assign(&mut self, o: Self) {
        self.v -= o.v;
        self.g -= o.g;
        self.h -= o.h;
    }
}

impl<const N: usize> Real for Dual2<N> {
    fn map(self, f: f64, df: f64, ddf: f64) -> Self {
        self.chain(f, df, ddf)
    }
    fn cst(x: f64) -> Self {
        Dual2::cst(x)
    }
    fn var(x: f64, i: usize) -> Self {
        Dual2::var(x, i)
    }
    fn val(&self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        // f' = 1/(2r), f'' = -1/(4 r^3)
        self.chain(r, 0.5 / r, -0.25 / (r * self.v))
    }
    fn ln(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(self.v.ln(), r, -r * r)
    }
    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }
    fn sq(self) -> Self {
        // (a^2)'' = 2 a h + 2 g g^T: one outer product instead of two.
        let mut h = self.h * (2.0 * self.v);
        h.ger(2.0, &self.g, &self.g, 1.0);
        Dual2 {
            v: self.v * self.v,
            g: self.g * (2.0 * self.v),
            h,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A composite of every operation:
    /// f(x, y, z) = ln(x y + 3) sqrt(z^2 + x) / (y - 4) - 2 x / z + 1 + 1/(4 z).
    fn f<T: Real>(x: T, y: T, z: T) -> T {
        let mut s = (x * y + 3.0).ln() * (z.sq() + x).sqrt() / (y - 4.0);
        s -= x * 2.0 / z;
        s += T::cst(1.0);
        -(-s) + z.recip() * 0.25
    }

    fn f64s(p: [f64; 3]) -> f64 {
        f(p[0], p[1], p[2])
    }

    const P: [f64; 3] = [0.7, 1.3, -0.9];

    fn fd_gradient(p: [f64; 3], h: f64) -> [f64; 3] {
        let mut g = [0.0; 3];
        for i in 0..3 {
            let (mut a, mut b) = (p, p);
            a[i] += h;
            b[i] -= h;
            g[i] = (f64s(a) - f64s(b)) / (2.0 * h);
        }
        g
    }

    #[test]
    fn dual1_gradient_matches_finite_differences() {
        let d = f(
            Dual1::<3>::var(P[0], 0),
            Dual1::var(P[1], 1),
            Dual1::var(P[2], 2),
        );
        assert_eq!(d.v, f64s(P));
        let g = fd_gradient(P, 1e-6);
        for (i, gi) in g.iter().enumerate() {
            assert!(
                (d.g[i] - gi).abs() < 1e-7 * (1.0 + gi.abs()),
                "{i}: {} vs {gi}",
                d.g[i]
            );
        }
    }

    #[test]
    fn dual2_hessian_matches_finite_differences_of_dual1() {
        let d = f(
            Dual2::<3>::var(P[0], 0),
            Dual2::var(P[1], 1),
            Dual2::var(P[2], 2),
        );
        assert_eq!(d.v, f64s(P));
        let h = 1e-5;
        for j in 0..3 {
            let grad_at = |dx: f64| {
                let mut p = P;
                p[j] += dx;
                f(
                    Dual1::<3>::var(p[0], 0),
                    Dual1::var(p[1], 1),
                    Dual1::var(p[2], 2),
                )
                .g
            };
            let col = (grad_at(h) - grad_at(-h)) / (2.0 * h);
            for i in 0..3 {
                assert!(
                    (d.h[(i, j)] - col[i]).abs() < 1e-7 * (1.0 + col[i].abs()),
                    "H[{i},{j}] {} vs {}",
                    d.h[(i, j)],
                    col[i]
                );
                assert_eq!(d.h[(i, j)], d.h[(j, i)]);
            }
            let g1 = grad_at(0.0);
            assert!((d.g - g1).norm() < 1e-14 * (1.0 + g1.norm()));
        }
    }

    #[test]
    fn dual2_closed_form() {
        // g(x, y) = x^2 y / (1 + y) with closed-form derivatives.
        let (x0, y0) = (1.7, 0.4);
        let (x, y) = (Dual2::<2>::var(x0, 0), Dual2::var(y0, 1));
        let d = x * x * y / (y + 1.0);
        let q = 1.0 + y0;
        assert!((d.v - x0 * x0 * y0 / q).abs() < 1e-15);
        let gx = 2.0 * x0 * y0 / q;
        let gy = x0 * x0 / (q * q);
        let hxx = 2.0 * y0 / q;
        let hxy = 2.0 * x0 / (q * q);
        let hyy = -2.0 * x0 * x0 / (q * q * q);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-14 * (1.0 + b.abs());
        assert!(close(d.g[0], gx) && close(d.g[1], gy));
        assert!(close(d.h[(0, 0)], hxx) && close(d.h[(0, 1)], hxy));
        assert!(close(d.h[(1, 0)], hxy) && close(d.h[(1, 1)], hyy));
        // sqrt, ln and recip against their closed forms at a point.
        let s = x.sqrt();
        assert!(close(s.g[0], 0.5 / x0.sqrt()));
        assert!(close(s.h[(0, 0)], -0.25 * x0.powf(-1.5)));
        let l = x.ln();
        assert!(close(l.g[0], 1.0 / x0) && close(l.h[(0, 0)], -1.0 / (x0 * x0)));
        let r = x.recip();
        assert!(close(r.g[0], -1.0 / (x0 * x0)));
        assert!(close(r.h[(0, 0)], 2.0 / (x0 * x0 * x0)));
        assert_eq!(r.h[(1, 1)], 0.0);
        // map with a function's derivatives agrees with the same function
        // through the operations: ln(d) of the expression above, in both
        // dual types.
        let m = d.map(d.v.ln(), 1.0 / d.v, -1.0 / (d.v * d.v));
        let o = d.ln();
        assert!(close(m.v, o.v));
        for i in 0..2 {
            assert!(close(m.g[i], o.g[i]));
            for j in 0..2 {
                assert!(close(m.h[(i, j)], o.h[(i, j)]));
            }
        }
        let d1 = Dual1::<2>::var(x0, 0) * Dual1::var(y0, 1);
        let m1 = d1.map(d1.v.ln(), 1.0 / d1.v, 0.0);
        let o1 = d1.ln();
        assert!(close(m1.v, o1.v) && close(m1.g[0], o1.g[0]) && close(m1.g[1], o1.g[1]));
    }
}
