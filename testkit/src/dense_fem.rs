//! Dense references written in the tests, from the scene's numbers only (none of the crate's
//! chains or dense assemblies): a dense FEM of the cables with the hidden cables' nodes
//! explicit ([`dense_with_hidden`], [`add_hidden`]), and the eigenpairs of a dense matrix
//! pair ([`dense_eig`]).
use cablevib::scene::{Cable, HiddenCable, Scene};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// One free cable of [`dense_with_hidden`]: its elements' 3 × 3 stiffness blocks (N/m, world
/// frame; one per element, anchor side first), each element's mass (kg), and the direction
/// along which the junction at the pulley moves (a cable with a hidden part only).
pub struct FreeCable {
    /// Element j's stiffness block, on [1 −1; −1 1].
    pub blocks: Vec<Matrix3<f64>>,
    /// Mass of one element, kg: consistent mass (m/6)[2I I; I 2I].
    pub element_mass_kg: f64,
    /// Unit direction of the junction's one DOF (unused without a hidden cable).
    pub junction_dir: Vector3<f64>,
}

/// The dense (K, M) of the scene's cables at an end-effector point mass, `n` elements per
/// free cable and per hidden cable, the free cables' elements given by `free(i, cable)`.
/// DOF order: the end-effector (0..3), then for each cable its n − 1 interior nodes from the
/// anchor (3 DOF each), then, when it has a hidden cable, the hidden cable's n − 1 interior
/// nodes from the drum and the junction at the pulley (one axial DOF each: the pulley holds
/// the junction transversely). Anchors and drums are fixed.
pub fn dense_with_hidden(
    scene: &Scene,
    n: usize,
    mut free: impl FnMut(usize, &Cable) -> FreeCable,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let per_cable = |c: &Cable| 3 * (n - 1) + c.hidden.map_or(0, |_| n);
    let ndof = 3 + scene.cables.iter().map(per_cable).sum::<usize>();
    let mut k = DMatrix::zeros(ndof, ndof);
    let mut m = DMatrix::zeros(ndof, ndof);
    for i in 0..3 {
        m[(i, i)] = scene.ee_mass_kg;
    }
    let mut base = 3;
    for (ci, c) in scene.cables.iter().enumerate() {
        let FreeCable {
            blocks,
            element_mass_kg: me,
            junction_dir: dir,
        } = free(ci, c);
        assert_eq!(blocks.len(), n, "cable {ci}: one block per element");
        let junction = c.hidden.map(|_| base + 3 * (n - 1) + n - 1);
        // Free node j → (first row, 3 × r map to its DOFs): 0 the anchor (fixed or the
        // junction, moving along `dir`), n the end-effector.
        let map = |j: usize| -> Option<(usize, DMatrix<f64>)> {
            if j == n {
                Some((0, DMatrix::identity(3, 3)))
            } else if j == 0 {
                junction.map(|r| (r, DMatrix::from_column_slice(3, 1, dir.as_slice())))
            } else {
                Some((base + 3 * (j - 1), DMatrix::identity(3, 3)))
            }
        };
        for (el, ke) in blocks.iter().enumerate() {
            let ke = DMatrix::from_fn(3, 3, |r, q| ke[(r, q)]);
            for (a, na) in [el, el + 1].into_iter().enumerate() {
                for (b, nb) in [el, el + 1].into_iter().enumerate() {
                    let (Some((ra, ga)), Some((rb, gb))) = (map(na), map(nb)) else {
                        continue;
                    };
                    let sign = if a == b { 1.0 } else { -1.0 };
                    let mc = if a == b { me / 3.0 } else { me / 6.0 };
                    let kk = ga.transpose() * &ke * &gb * sign;
                    let mm = ga.transpose() * &gb * mc;
                    for r in 0..kk.nrows() {
                        for q in 0..kk.ncols() {
                            k[(ra + r, rb + q)] += kk[(r, q)];
                            m[(ra + r, rb + q)] += mm[(r, q)];
                        }
                    }
                }
            }
        }
        if let Some(hc) = c.hidden {
            add_hidden(&mut k, &mut m, base + 3 * (n - 1), n, &hc);
        }
        base += per_cable(c);
    }
    (k, m)
}

/// The hidden cable `h` as `n` axial elements from the drum (node 0, fixed) to the junction
/// (node n), its nodes 1 ..= n at rows `first` ..
pub fn add_hidden(
    k: &mut DMatrix<f64>,
    m: &mut DMatrix<f64>,
    first: usize,
    n: usize,
    h: &HiddenCable,
) {
    let lh = h.length_m / n as f64;
    let (kh, mh) = (h.ea_n() / lh, h.mass_per_length_kg_m * lh);
    let at = |j: usize| first + j - 1;
    for el in 0..n {
        for (a, na) in [el, el + 1].into_iter().enumerate() {
            for (b, nb) in [el, el + 1].into_iter().enumerate() {
                if na == 0 || nb == 0 {
                    continue;
                }
                let same = a == b;
                k[(at(na), at(nb))] += if same { kh } else { -kh };
                m[(at(na), at(nb))] += mh / if same { 3.0 } else { 6.0 };
            }
        }
    }
}

/// Every eigenpair of K u = λ M u, λ ascending, the columns u M-orthonormal: M = L Lᵀ
/// (Cholesky), the symmetric eigen-solve of L⁻¹ K L⁻ᵀ (symmetrised), u = L⁻ᵀ v.
pub fn dense_eig(k: &DMatrix<f64>, m: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let l = m.clone().cholesky().expect("M positive definite").l();
    let a = l.solve_lower_triangular(k).unwrap();
    let c = l.solve_lower_triangular(&a.transpose()).unwrap();
    let c = (&c + c.transpose()) * 0.5;
    let e = nalgebra::SymmetricEigen::new(c);
    let mut idx: Vec<usize> = (0..e.eigenvalues.len()).collect();
    idx.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
    let u = l
        .transpose()
        .solve_upper_triangular(&e.eigenvectors)
        .unwrap();
    let lam = idx.iter().map(|&i| e.eigenvalues[i]).collect();
    let mut v = DMatrix::zeros(u.nrows(), idx.len());
    for (c, &i) in idx.iter().enumerate() {
        v.set_column(c, &u.column(i));
    }
    (lam, v)
}
