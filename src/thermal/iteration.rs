//! The iteration matrix W = C − d·h·J of the implicit stages: its Jacobian, its
//! factorisation and the solves with it. Three representations, chosen per network by
//! [`LinearSolver`] (`auto`: dense up to 40 nodes, iterative above):
//!
//! - **dense**: the n×n matrix, LU with partial pivoting and an explicit inverse, so a
//!   solve is one matrix-vector product. O(n³) per factorisation and O(n²) per solve
//!   and in memory: the fastest for the networks of a mechanism (tens of nodes).
//! - **iterative**: conjugate gradients on the network's own pattern (a diagonal and
//!   a pair of entries per node-to-node link), preconditioned by an incomplete
//!   Cholesky factor IC(0). W is symmetric positive definite once each radiative
//!   link's two off-diagonal entries 4σεA·T³ (one per end) are replaced by their
//!   geometric mean; W only steers Newton's convergence, never the solution it
//!   converges to, and the solutions agree with the dense solver's to ~1e-11 K
//!   (`tests/core_large_networks.rs`). The mass matrix C keeps W well conditioned
//!   whatever the size, so a solve takes about six iterations of O(links) work: the
//!   cost per step grows about linearly with the network. A network that needs more
//!   than 400 iterations in a solve is switched to the sparse LU.
//! - **sparse**: faer's sparse LU of the exact W with a fill-reducing (COLAMD) ordering
//!   and the symbolic analysis done once per network; a factorisation when h or J
//!   changes is numeric only. Cheap for chains and trees, but the factors of a 3-D
//!   lattice or a random graph fill in (see `docs/performance.md`).
//!
//! All three are sequential and deterministic.

// Index loops over rows and nodes mirror the algorithms; kept as they are.
#![allow(clippy::needless_range_loop)]

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::SymbolicSparseColMat;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::{
    LuRef, LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu,
};
use faer::{ColMut, Conj, Par};

use super::Compiled;
use super::lu::{Lu, Singular};

/// How the implicit stages solve their linear systems. Serialised as its name
/// ("auto", "dense", "sparse", "iterative").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolver {
    /// Dense up to [`AUTO_SPARSE_ABOVE_NODES`] diffusion nodes, iterative above.
    #[default]
    Auto,
    /// LU of the full matrix with an explicit inverse.
    Dense,
    /// Sparse LU (faer) of the exact matrix on the network's pattern.
    Sparse,
    /// Conjugate gradients preconditioned by an incomplete Cholesky factor, on the
    /// symmetric form of the matrix; falls back to `Sparse` when it needs more than
    /// 400 iterations in a solve.
    Iterative,
}

impl LinearSolver {
    pub fn name(self) -> &'static str {
        match self {
            LinearSolver::Auto => "auto",
            LinearSolver::Dense => "dense",
            LinearSolver::Sparse => "sparse",
            LinearSolver::Iterative => "iterative",
        }
    }

    /// What a network of `n` diffusion nodes is solved with (`Auto` resolved).
    pub fn resolve(self, n: usize) -> LinearSolver {
        match self {
            LinearSolver::Auto if n > AUTO_SPARSE_ABOVE_NODES => LinearSolver::Iterative,
            LinearSolver::Auto => LinearSolver::Dense,
            other => other,
        }
    }
}

/// Above this many diffusion nodes `auto` solves iteratively (the crossover measured
/// with `orbitlash bench --scaling`, see `docs/performance.md`).
pub const AUTO_SPARSE_ABOVE_NODES: usize = 40;

/// Most conjugate-gradient iterations in one solve. A network that needs more (very
/// stiff and irregular) is switched to the sparse direct solver for the rest of the
/// run.
const KRYLOV_MAX_ITERATIONS: u32 = 400;

/// Conjugate gradients stop when the residual is below this fraction of the right-hand
/// side: far below what the Newton iterations resolve (1 % of the step tolerance), so
/// that the solution does not depend on the linear solver.
const KRYLOV_RELATIVE_TOLERANCE: f64 = 1e-10;

/// Most diffusion nodes the dense solver takes: its W and explicit inverse take
/// 16 n² bytes (144 MB here) and a factorisation 2 n³ operations (~2.5 s per step at
/// 3000 nodes, minutes beyond).
pub const DENSE_MAX_NODES: usize = 3000;

/// Most floating-point operations a factorisation of the sparse LU may take (as
/// estimated by [`direct_fill_estimate`]; the LU runs at ~1e8 of them per second): a
/// few seconds. A random graph of 2000 nodes needs 1.4e8 (1.3 s per factorisation), of
/// 10 000 nodes 1.9e10 (4 minutes), a 10 000-node lattice 3e9.
pub const SPARSE_MAX_FLOPS: f64 = 3e8;

/// The network's pattern: the diagonal and both entries of every node-to-node link,
/// compressed by columns (row indices sorted). Structurally symmetric, so it is also
/// the compressed-rows form.
fn pattern(c: &Compiled) -> (Vec<usize>, Vec<usize>) {
    let n = c.n;
    let mut adj: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
    for &(i, j, _) in c.lin_nn.iter().chain(&c.rad_nn) {
        adj[i].push(j);
        adj[j].push(i);
    }
    let mut ptr = Vec::with_capacity(n + 1);
    let mut idx = Vec::new();
    ptr.push(0);
    for rows in &mut adj {
        rows.sort_unstable();
        rows.dedup();
        idx.extend_from_slice(rows);
        ptr.push(idx.len());
    }
    (ptr, idx)
}

/// (entries, floating-point operations) of the Cholesky factor of the network's
/// pattern under a minimum-degree ordering: the fill and the work a sparse direct
/// factorisation of W meets (the LU's are of the same order or worse). Cheap: a
/// symbolic analysis, no numbers.
pub fn direct_fill_estimate(c: &Compiled) -> (usize, f64) {
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
    };
    let (ptr, idx) = pattern(c);
    let n = c.n;
    let pattern = SymbolicSparseColMat::new_checked(n, n, ptr, None, idx);
    factorize_symbolic_cholesky(
        pattern.as_ref(),
        faer::Side::Upper,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        },
    )
    .map_or((usize::MAX, f64::INFINITY), |s| {
        let flops = match s.raw() {
            SymbolicCholeskyRaw::Simplicial(l) => l
                .col_ptr()
                .windows(2)
                .map(|w| {
                    let c = (w[1] - w[0]) as f64;
                    c * c
                })
                .sum(),
            SymbolicCholeskyRaw::Supernodal(_) => f64::INFINITY,
        };
        (s.len_val(), flops)
    })
}

/// W = C − d·h·J, factorised (see the module docs).
pub struct IterationMatrix {
    inner: Inner,
}

enum Inner {
    Dense(Dense),
    Sparse(Box<Sparse>),
    Krylov(Box<Krylov>),
}

/// Conjugate gradients on the symmetric form of W (see [`Krylov::set_jacobian`]),
/// preconditioned by an incomplete Cholesky factor IC(0) (by the diagonal should IC(0)
/// break down). CSR storage of the full pattern.
struct Krylov {
    n: usize,
    row_ptr: Vec<usize>,
    col: Vec<usize>,
    diag: Vec<usize>,
    lin: Vec<[usize; 4]>,
    rad: Vec<[usize; 4]>,
    jac: Vec<f64>,
    w: Vec<f64>,
    inv_diag: Vec<f64>,
    /// Incomplete Cholesky factor IC(0) of W on the lower pattern (CSR: for row i,
    /// `l_ptr[i]..l_ptr[i+1]` over columns `l_col`, the diagonal last).
    l_ptr: Vec<usize>,
    l_col: Vec<usize>,
    /// Where each entry of L sits in `w`.
    l_src: Vec<usize>,
    l_val: Vec<f64>,
    /// IC(0) exists for the current W (else the diagonal preconditions).
    ic_ok: bool,
    x: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    /// CG iterations over the run (for statistics).
    iterations: u64,
    solves: u64,
    max_iterations: u32,
    /// A solve reached `max_iterations`: switch to the direct solver.
    struggled: bool,
}

struct Dense {
    n: usize,
    /// ∂f/∂T, row-major.
    jac: Vec<f64>,
    lu: Lu,
}

struct Sparse {
    pattern: SymbolicSparseColMat<usize>,
    /// Value slot of each diagonal entry.
    diag: Vec<usize>,
    /// Value slots (i,i), (i,j), (j,j), (j,i) of each node-to-node link, in the order of
    /// `Compiled::lin_nn` and `Compiled::rad_nn`.
    lin: Vec<[usize; 4]>,
    rad: Vec<[usize; 4]>,
    /// ∂f/∂T and W on the pattern (CSC order).
    jac: Vec<f64>,
    w: Vec<f64>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    mem: MemBuffer,
}

impl IterationMatrix {
    /// The matrix of `compiled`'s network, dense or sparse as `choice` says.
    pub fn new(compiled: &Compiled, choice: LinearSolver) -> IterationMatrix {
        let n = compiled.n;
        let inner = match choice.resolve(n) {
            LinearSolver::Iterative => Inner::Krylov(Box::new(Krylov::new(compiled))),
            LinearSolver::Sparse => Inner::Sparse(Box::new(Sparse::new(compiled))),
            _ => Inner::Dense(Dense {
                n,
                jac: vec![0.0; n * n],
                lu: Lu::new(n),
            }),
        };
        IterationMatrix { inner }
    }

    /// Dense, sparse or iterative (never `Auto`: the choice made).
    pub fn kind(&self) -> LinearSolver {
        match self.inner {
            Inner::Dense(_) => LinearSolver::Dense,
            Inner::Sparse(_) => LinearSolver::Sparse,
            Inner::Krylov(_) => LinearSolver::Iterative,
        }
    }

    /// (solves, Krylov iterations) so far; iterations are 0 for direct solvers.
    pub fn solve_counts(&self) -> (u64, u64) {
        match &self.inner {
            Inner::Krylov(k) => (k.solves, k.iterations),
            _ => (0, 0),
        }
    }

    /// Entries of the factors (n² for dense).
    pub fn factor_entries(&self) -> usize {
        match &self.inner {
            Inner::Dense(d) => d.n * d.n,
            Inner::Sparse(s) => s.factor_entries(),
            Inner::Krylov(k) => k.w.len(),
        }
    }

    /// Switches an iterative solver to the sparse LU (as its fallback does).
    pub fn turn_sparse(&mut self, compiled: &Compiled) {
        self.inner = Inner::Sparse(Box::new(Sparse::new(compiled)));
    }

    /// Evaluates the Jacobian ∂f/∂T at `temps_k`. An iterative solver that struggled
    /// (see [`LinearSolver::Iterative`]) becomes a sparse direct one here.
    pub fn set_jacobian(&mut self, compiled: &Compiled, temps_k: &[f64]) {
        if let Inner::Krylov(k) = &mut self.inner
            && k.struggled
        {
            if direct_fill_estimate(compiled).1 <= SPARSE_MAX_FLOPS {
                self.inner = Inner::Sparse(Box::new(Sparse::new(compiled)));
            } else {
                // a direct factorisation would cost more than iterating longer
                k.struggled = false;
                k.max_iterations = k.max_iterations.saturating_mul(10);
            }
        }
        match &mut self.inner {
            Inner::Dense(d) => compiled.jacobian(temps_k, &mut d.jac),
            Inner::Sparse(s) => s.set_jacobian(compiled, temps_k),
            Inner::Krylov(k) => k.set_jacobian(compiled, temps_k),
        }
    }

    /// Forms W = diag(cap) − dh·J and factorises it.
    pub fn factor(&mut self, cap: &[f64], dh: f64) -> Result<(), Singular> {
        match &mut self.inner {
            Inner::Dense(d) => {
                let n = d.n;
                let w = d.lu.matrix_mut();
                for i in 0..n {
                    for j in 0..n {
                        w[i * n + j] = -dh * d.jac[i * n + j];
                    }
                    w[i * n + i] += cap[i];
                }
                d.lu.factor()
            }
            Inner::Sparse(s) => s.factor(cap, dh),
            Inner::Krylov(k) => k.factor(cap, dh),
        }
    }

    /// Solves W x = b in place with the last factorisation.
    pub fn solve(&mut self, b: &mut [f64]) {
        match &mut self.inner {
            Inner::Dense(d) => d.lu.solve(b),
            Inner::Sparse(s) => s.solve(b),
            Inner::Krylov(k) => k.solve(b),
        }
    }
}

impl Sparse {
    fn new(c: &Compiled) -> Sparse {
        let n = c.n;
        let (col_ptr, row_idx) = pattern(c);
        let slot = |row: usize, col: usize| {
            let (a, b) = (col_ptr[col], col_ptr[col + 1]);
            a + row_idx[a..b]
                .binary_search(&row)
                .expect("every link is in the pattern")
        };
        let diag: Vec<usize> = (0..n).map(|i| slot(i, i)).collect();
        let slots = |list: &[(usize, usize, f64)]| -> Vec<[usize; 4]> {
            list.iter()
                .map(|&(i, j, _)| [slot(i, i), slot(i, j), slot(j, j), slot(j, i)])
                .collect()
        };
        let (lin, rad) = (slots(&c.lin_nn), slots(&c.rad_nn));
        let nnz = row_idx.len();
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        // Simplicial: sequential, and the numeric factorisation reuses its buffers.
        let symbolic = factorize_symbolic_lu(
            pattern.as_ref(),
            LuSymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
                ..Default::default()
            },
        )
        .expect("symbolic LU of a square pattern with a full diagonal");
        let mem = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]));
        Sparse {
            pattern,
            diag,
            lin,
            rad,
            jac: vec![0.0; nnz],
            w: vec![0.0; nnz],
            symbolic,
            numeric: NumericLu::new(),
            mem,
        }
    }

    fn factor_entries(&self) -> usize {
        // the factors' entries are only known after a numeric factorisation; the
        // pattern's are a lower bound
        self.w.len()
    }

    fn set_jacobian(&mut self, c: &Compiled, t: &[f64]) {
        self.jac.iter_mut().for_each(|x| *x = 0.0);
        let jac = &mut self.jac;
        let mut link = |s: &[usize; 4], d_i: f64, d_j: f64| {
            // q = flow into i: ∂q/∂Ti = −d_i, ∂q/∂Tj = d_j; the reverse for j.
            jac[s[0]] -= d_i;
            jac[s[1]] += d_j;
            jac[s[2]] -= d_j;
            jac[s[3]] += d_i;
        };
        for (s, &(_, _, g)) in self.lin.iter().zip(&c.lin_nn) {
            link(s, g, g);
        }
        for (s, &(i, j, k)) in self.rad.iter().zip(&c.rad_nn) {
            let (ti, tj) = (t[i], t[j]);
            link(s, 4.0 * k * ti * ti * ti, 4.0 * k * tj * tj * tj);
        }
        for &(i, _, g) in &c.lin_nb {
            self.jac[self.diag[i]] -= g;
        }
        for &(i, _, k) in &c.rad_nb {
            let ti = t[i];
            self.jac[self.diag[i]] -= 4.0 * k * ti * ti * ti;
        }
    }

    fn factor(&mut self, cap: &[f64], dh: f64) -> Result<(), Singular> {
        for (w, j) in self.w.iter_mut().zip(&self.jac) {
            *w = -dh * j;
        }
        for (&d, c) in self.diag.iter().zip(cap) {
            self.w[d] += c;
        }
        if self.w.iter().any(|x| !x.is_finite()) {
            return Err(Singular);
        }
        let a = faer::sparse::SparseColMatRef::new(self.pattern.as_ref(), &self.w);
        self.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                a,
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .map(|_| ())
            .map_err(|_| Singular)
    }

    fn solve(&mut self, b: &mut [f64]) {
        let lu = LuRef::new_unchecked(&self.symbolic, &self.numeric);
        lu.solve_in_place_with_conj(
            Conj::No,
            ColMut::from_slice_mut(b).as_mat_mut(),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
    }
}

impl Krylov {
    fn new(c: &Compiled) -> Krylov {
        let n = c.n;
        let (row_ptr, col) = pattern(c);
        let slot = |row: usize, c: usize| {
            let (a, b) = (row_ptr[row], row_ptr[row + 1]);
            a + col[a..b].binary_search(&c).expect("in the pattern")
        };
        let diag: Vec<usize> = (0..n).map(|i| slot(i, i)).collect();
        let slots = |list: &[(usize, usize, f64)]| -> Vec<[usize; 4]> {
            list.iter()
                .map(|&(i, j, _)| [slot(i, i), slot(i, j), slot(j, j), slot(j, i)])
                .collect()
        };
        let (lin, rad) = (slots(&c.lin_nn), slots(&c.rad_nn));
        let nnz = col.len();
        let mut l_ptr = vec![0];
        let mut l_col = Vec::new();
        let mut l_src = Vec::new();
        for i in 0..n {
            for k in row_ptr[i]..row_ptr[i + 1] {
                if col[k] <= i {
                    l_col.push(col[k]);
                    l_src.push(k);
                }
            }
            l_ptr.push(l_col.len());
        }
        let l_val = vec![0.0; l_col.len()];
        Krylov {
            l_ptr,
            l_col,
            l_src,
            l_val,
            ic_ok: false,
            n,
            row_ptr,
            col,
            diag,
            lin,
            rad,
            jac: vec![0.0; nnz],
            w: vec![0.0; nnz],
            inv_diag: vec![0.0; n],
            x: vec![0.0; n],
            r: vec![0.0; n],
            z: vec![0.0; n],
            p: vec![0.0; n],
            q: vec![0.0; n],
            iterations: 0,
            solves: 0,
            max_iterations: KRYLOV_MAX_ITERATIONS,
            struggled: false,
        }
    }

    /// The symmetric form of ∂f/∂T: a radiative link's off-diagonal entries 4σεA T_j³
    /// and 4σεA T_i³ become their geometric mean (the diagonal stays exact), so that
    /// W is symmetric positive definite and CG applies. The iteration matrix only
    /// steers Newton's convergence, never the solution it converges to.
    fn set_jacobian(&mut self, c: &Compiled, t: &[f64]) {
        self.jac.iter_mut().for_each(|x| *x = 0.0);
        let jac = &mut self.jac;
        for (s, &(_, _, g)) in self.lin.iter().zip(&c.lin_nn) {
            jac[s[0]] -= g;
            jac[s[1]] += g;
            jac[s[2]] -= g;
            jac[s[3]] += g;
        }
        for (s, &(i, j, k)) in self.rad.iter().zip(&c.rad_nn) {
            let (a, b) = (4.0 * k * t[i].powi(3), 4.0 * k * t[j].powi(3));
            let m = (a * b).sqrt();
            jac[s[0]] -= a;
            jac[s[1]] += m;
            jac[s[2]] -= b;
            jac[s[3]] += m;
        }
        for &(i, _, g) in &c.lin_nb {
            self.jac[self.diag[i]] -= g;
        }
        for &(i, _, k) in &c.rad_nb {
            self.jac[self.diag[i]] -= 4.0 * k * t[i].powi(3);
        }
    }

    fn factor(&mut self, cap: &[f64], dh: f64) -> Result<(), Singular> {
        for (w, j) in self.w.iter_mut().zip(&self.jac) {
            *w = -dh * j;
        }
        for (i, (&d, c)) in self.diag.iter().zip(cap).enumerate() {
            self.w[d] += c;
            let v = self.w[d];
            if !(v.is_finite() && v > 0.0) {
                return Err(Singular);
            }
            self.inv_diag[i] = 1.0 / v;
        }
        self.incomplete_cholesky();
        Ok(())
    }

    /// IC(0): L Lᵀ ≈ W with L on the lower pattern of W. W is an M-matrix here
    /// (positive diagonal, non-positive off-diagonal entries, diagonally dominant), for
    /// which IC(0) exists; should a pivot still fail, the preconditioner falls back to
    /// the diagonal.
    fn incomplete_cholesky(&mut self) {
        let n = self.n;
        for (v, &s) in self.l_val.iter_mut().zip(&self.l_src) {
            *v = self.w[s];
        }
        for i in 0..n {
            let (a, b) = (self.l_ptr[i], self.l_ptr[i + 1]);
            // off-diagonal entries L[i,j], j < i, in increasing j
            for k in a..b - 1 {
                let j = self.l_col[k];
                let (ja, jb) = (self.l_ptr[j], self.l_ptr[j + 1] - 1);
                // Σ_{m<j} L[i,m] L[j,m] over the common pattern (both rows sorted)
                let (mut p, mut q, mut s) = (a, ja, 0.0);
                while p < k && q < jb {
                    match self.l_col[p].cmp(&self.l_col[q]) {
                        std::cmp::Ordering::Less => p += 1,
                        std::cmp::Ordering::Greater => q += 1,
                        std::cmp::Ordering::Equal => {
                            s += self.l_val[p] * self.l_val[q];
                            p += 1;
                            q += 1;
                        }
                    }
                }
                self.l_val[k] = (self.l_val[k] - s) / self.l_val[jb];
                // (row j is finished: its diagonal still holds L[j,j] here, the
                // reciprocals are taken after the whole factor)
            }
            let s: f64 = self.l_val[a..b - 1].iter().map(|x| x * x).sum();
            let d = self.l_val[b - 1] - s;
            if !(d > 0.0 && d.is_finite()) {
                self.ic_ok = false;
                return;
            }
            self.l_val[b - 1] = d.sqrt();
        }
        // The sweeps multiply by the reciprocal: a division on the dependency chain
        // from row to row costs several times a multiplication.
        for i in 0..n {
            let k = self.l_ptr[i + 1] - 1;
            self.l_val[k] = 1.0 / self.l_val[k];
        }
        self.ic_ok = true;
    }

    /// z = M⁻¹ r: IC(0) when it exists, else the diagonal.
    fn precondition(
        ic_ok: bool,
        (l_ptr, l_col, l_val): (&[usize], &[usize], &[f64]),
        inv_diag: &[f64],
        r: &[f64],
        z: &mut [f64],
    ) {
        let n = r.len();
        if !ic_ok {
            for i in 0..n {
                z[i] = r[i] * inv_diag[i];
            }
            return;
        }
        // L y = r
        for i in 0..n {
            let (a, b) = (l_ptr[i], l_ptr[i + 1]);
            let mut s = r[i];
            for k in a..b - 1 {
                s -= l_val[k] * z[l_col[k]];
            }
            z[i] = s * l_val[b - 1];
        }
        // Lᵀ z = y
        for i in (0..n).rev() {
            let (a, b) = (l_ptr[i], l_ptr[i + 1]);
            z[i] *= l_val[b - 1];
            let zi = z[i];
            for k in a..b - 1 {
                z[l_col[k]] -= l_val[k] * zi;
            }
        }
    }

    fn matvec(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            let (a, b) = (self.row_ptr[i], self.row_ptr[i + 1]);
            *yi = self.w[a..b]
                .iter()
                .zip(&self.col[a..b])
                .map(|(w, &c)| w * x[c])
                .sum();
        }
    }

    fn solve(&mut self, b: &mut [f64]) {
        let n = self.n;
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let bnorm = dot(b, b).sqrt();
        self.solves += 1;
        if bnorm == 0.0 {
            return;
        }
        // x0 = M⁻¹ b
        Self::precondition(
            self.ic_ok,
            (&self.l_ptr, &self.l_col, &self.l_val),
            &self.inv_diag,
            b,
            &mut self.x,
        );
        let mut q = std::mem::take(&mut self.q);
        self.matvec(&self.x, &mut q);
        for i in 0..n {
            self.r[i] = b[i] - q[i];
        }
        Self::precondition(
            self.ic_ok,
            (&self.l_ptr, &self.l_col, &self.l_val),
            &self.inv_diag,
            &self.r,
            &mut self.z,
        );
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        let mut converged = false;
        for _ in 0..self.max_iterations {
            if dot(&self.r, &self.r).sqrt() <= KRYLOV_RELATIVE_TOLERANCE * bnorm {
                converged = true;
                break;
            }
            self.iterations += 1;
            self.matvec(&self.p, &mut q);
            let alpha = rz / dot(&self.p, &q);
            for i in 0..n {
                self.x[i] += alpha * self.p[i];
                self.r[i] -= alpha * q[i];
            }
            Self::precondition(
                self.ic_ok,
                (&self.l_ptr, &self.l_col, &self.l_val),
                &self.inv_diag,
                &self.r,
                &mut self.z,
            );
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                self.p[i] = self.z[i] + beta * self.p[i];
            }
        }
        self.q = q;
        if !converged && dot(&self.r, &self.r).sqrt() > KRYLOV_RELATIVE_TOLERANCE * bnorm {
            // The best approximation goes back; Newton will judge it, and the next
            // Jacobian evaluation switches to the direct solver.
            self.struggled = true;
        }
        b.copy_from_slice(&self.x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal::{Conductor, DiffusionNode, Network, NodeRef, Radiator};

    /// A ring of 7 nodes with linear and radiative links and links to space.
    fn network() -> Network {
        let n = 7;
        let node = |i: usize| DiffusionNode {
            name: format!("n{i}"),
            capacitance_j_per_k: 1.0 + i as f64,
            initial_temperature_k: 250.0 + 10.0 * i as f64,
            radius_m: None,
        };
        Network {
            nodes: (0..n).map(node).collect(),
            boundaries: vec![crate::thermal::BoundaryNode {
                name: "space".into(),
                temperature_k: crate::orbit::Profile::Constant(3.0),
            }],
            conductors: (0..n)
                .map(|i| Conductor {
                    a: NodeRef::Diffusion(i),
                    b: NodeRef::Diffusion((i + 1) % n),
                    conductance_w_per_k: 0.3 + 0.1 * i as f64,
                })
                .collect(),
            radiators: (0..n)
                .map(|i| Radiator {
                    a: NodeRef::Diffusion(i),
                    b: if i % 2 == 0 {
                        NodeRef::Boundary(0)
                    } else {
                        NodeRef::Diffusion((i + 3) % n)
                    },
                    emissivity_area_m2: 0.01 * (1 + i) as f64,
                })
                .collect(),
            loads: vec![],
            heaters: vec![],
        }
    }

    #[test]
    fn core_sparse_solves_match_dense() {
        let net = network();
        let c = Compiled::new(&net);
        let temps = net.initial_temperatures_k();
        let cap = c.capacitance_j_per_k.clone();
        let mut dense = IterationMatrix::new(&c, LinearSolver::Dense);
        let mut sparse = IterationMatrix::new(&c, LinearSolver::Sparse);
        assert_eq!(
            (dense.kind().name(), sparse.kind().name()),
            ("dense", "sparse")
        );
        assert_eq!(
            IterationMatrix::new(&c, LinearSolver::Auto).kind().name(),
            "dense"
        );
        for dh in [0.1, 30.0, 3000.0] {
            for m in [&mut dense, &mut sparse] {
                m.set_jacobian(&c, &temps);
                m.factor(&cap, dh).unwrap();
            }
            let b: Vec<f64> = (0..7).map(|i| (i as f64 - 2.5) * 1.7).collect();
            let (mut x, mut y) = (b.clone(), b.clone());
            dense.solve(&mut x);
            sparse.solve(&mut y);
            for (p, q) in x.iter().zip(&y) {
                assert!(
                    (p - q).abs() < 1e-12 * (1.0 + p.abs()),
                    "{p} vs {q} at dh = {dh}"
                );
            }
        }
    }

    /// With only linear links W is symmetric, and CG must give the exact solution.
    #[test]
    fn core_iterative_solves_a_linear_network_exactly_and_falls_back() {
        let mut net = network();
        net.radiators
            .retain(|r| matches!(r.b, NodeRef::Boundary(_)));
        let c = Compiled::new(&net);
        let temps = net.initial_temperatures_k();
        let cap = c.capacitance_j_per_k.clone();
        let mut dense = IterationMatrix::new(&c, LinearSolver::Dense);
        let mut cg = IterationMatrix::new(&c, LinearSolver::Iterative);
        assert_eq!(cg.kind().name(), "iterative");
        for m in [&mut dense, &mut cg] {
            m.set_jacobian(&c, &temps);
            m.factor(&cap, 300.0).unwrap();
        }
        let b: Vec<f64> = (0..7).map(|i| 1.0 + (i * i) as f64).collect();
        let (mut x, mut y) = (b.clone(), b.clone());
        dense.solve(&mut x);
        cg.solve(&mut y);
        for (p, q) in x.iter().zip(&y) {
            assert!((p - q).abs() < 1e-8 * p.abs(), "{p} vs {q}");
        }
        // one iteration allowed: the solver gives up and turns direct
        if let Inner::Krylov(k) = &mut cg.inner {
            k.max_iterations = 1;
            // IC(0) of a ring is not exact: one iteration cannot converge
        }
        let mut y = b.clone();
        cg.solve(&mut y);
        cg.set_jacobian(&c, &temps);
        assert_eq!(cg.kind().name(), "sparse");
        cg.factor(&cap, 300.0).unwrap();
        let mut y = b.clone();
        cg.solve(&mut y);
        for (p, q) in x.iter().zip(&y) {
            assert!((p - q).abs() < 1e-10 * p.abs(), "{p} vs {q}");
        }
    }
}
