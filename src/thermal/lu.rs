//! Dense LU factorisation with partial pivoting, in place, for the small iteration
//! matrices of the implicit solver (no allocation after construction).

#[derive(Debug, Clone)]
pub struct Lu {
    n: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
    /// The explicit inverse, formed from the factors by row operations. The solver
    /// reuses one factorisation for many solves; for the small, diagonally dominant
    /// matrices here a solve is then a matrix-vector product of independent dot
    /// products instead of two latency-bound triangular sweeps.
    inv: Vec<f64>,
    scratch: Vec<f64>,
}

/// The matrix is singular to working precision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Singular;

impl Lu {
    pub fn new(n: usize) -> Lu {
        Lu {
            n,
            a: vec![0.0; n * n],
            piv: vec![0; n],
            inv: vec![0.0; n * n],
            scratch: vec![0.0; n],
        }
    }

    /// Row-major storage to fill before [`Lu::factor`].
    pub fn matrix_mut(&mut self) -> &mut [f64] {
        &mut self.a
    }

    pub fn factor(&mut self) -> Result<(), Singular> {
        let n = self.n;
        let a = &mut self.a;
        for k in 0..n {
            let mut p = k;
            let mut best = a[k * n + k].abs();
            for i in k + 1..n {
                let v = a[i * n + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if best == 0.0 || !best.is_finite() {
                return Err(Singular);
            }
            self.piv[k] = p;
            if p != k {
                let (top, bottom) = a.split_at_mut(p * n);
                top[k * n..k * n + n].swap_with_slice(&mut bottom[..n]);
            }
            let (upper, lower) = a.split_at_mut((k + 1) * n);
            let pivot_row = &upper[k * n..k * n + n];
            let inv = 1.0 / pivot_row[k];
            for row in lower.chunks_exact_mut(n) {
                let l = row[k] * inv;
                row[k] = l;
                if l != 0.0 {
                    for (x, &u) in row[k + 1..].iter_mut().zip(&pivot_row[k + 1..]) {
                        *x -= l * u;
                    }
                }
            }
        }
        // inv = U⁻¹ L⁻¹ P, by row operations on P·I.
        let inv = &mut self.inv;
        inv.iter_mut().for_each(|x| *x = 0.0);
        for i in 0..n {
            inv[i * n + i] = 1.0;
        }
        for (k, &p) in self.piv.iter().enumerate() {
            if p != k {
                let (top, bottom) = inv.split_at_mut(p * n);
                top[k * n..k * n + n].swap_with_slice(&mut bottom[..n]);
            }
        }
        for j in 0..n {
            let (upper, lower) = inv.split_at_mut((j + 1) * n);
            let src = &upper[j * n..];
            for (i, row) in (j + 1..n).zip(lower.chunks_exact_mut(n)) {
                let l = a[i * n + j];
                if l != 0.0 {
                    for (x, &y) in row.iter_mut().zip(src) {
                        *x -= l * y;
                    }
                }
            }
        }
        for j in (0..n).rev() {
            let (upper, lower) = inv.split_at_mut(j * n);
            let src = &mut lower[..n];
            let d = 1.0 / a[j * n + j];
            src.iter_mut().for_each(|x| *x *= d);
            for (i, row) in upper.chunks_exact_mut(n).enumerate() {
                let u = a[i * n + j];
                if u != 0.0 {
                    for (x, &y) in row.iter_mut().zip(src.iter()) {
                        *x -= u * y;
                    }
                }
            }
        }
        Ok(())
    }

    /// Solves A x = b in place.
    pub fn solve(&mut self, b: &mut [f64]) {
        let n = self.n;
        assert_eq!(b.len(), n);
        for (xi, row) in self.scratch.iter_mut().zip(self.inv.chunks_exact(n)) {
            *xi = row.iter().zip(b.iter()).map(|(a, v)| a * v).sum();
        }
        b.copy_from_slice(&self.scratch);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn val_second_method_lu_solves_against_nalgebra() {
        let n = 6;
        let m = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                3.0 + i as f64
            } else {
                ((i * 7 + j * 3) % 5) as f64 - 2.0
            }
        });
        let b = nalgebra::DVector::from_fn(n, |i, _| i as f64 - 1.5);
        let want = m.clone().lu().solve(&b).unwrap();
        let mut lu = Lu::new(n);
        for i in 0..n {
            for j in 0..n {
                lu.matrix_mut()[i * n + j] = m[(i, j)];
            }
        }
        lu.factor().unwrap();
        let mut x: Vec<f64> = b.iter().copied().collect();
        lu.solve(&mut x);
        for i in 0..n {
            assert!((x[i] - want[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn core_lu_reports_singular() {
        let mut lu = Lu::new(2);
        lu.matrix_mut().copy_from_slice(&[1.0, 2.0, 2.0, 4.0]);
        assert_eq!(lu.factor(), Err(Singular));
    }
}
