//! `Estimator.sweep` and `cablevib.sweep`: many poses in one call, numpy arrays in and out,
//! the GIL released and the poses spread over worker threads.
//!
//! The poses are cut into chunks of `chunk_poses` consecutive poses (the last one shorter).
//! Each chunk is evaluated in order by one estimator that starts as a copy of the estimator
//! as it was built (`Estimator(scene)`, before any `update`), warm-started from pose to pose
//! within the chunk. A chunk's results therefore depend on its poses alone: not on which
//! worker ran it, nor on the thread count, and they are bit for bit those of the loop
//! `for each chunk: e = Estimator(scene); [e.update(p, q, t) for p, q, t in chunk]`.
//!
//! Arrays cross as raw float64 bytes (`numpy.ascontiguousarray(..).tobytes()` in,
//! `numpy.frombuffer(bytearray)` out): every f64 crosses unchanged.

use crate::error::CablevibError;
use cablevib::estimator::{Estimate, Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::Scene;
use cablevib::study::points::MAX_THREADS;
use nalgebra::Vector3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyBytes, PyDict, PyList, PyString};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Default poses per chunk: long enough that the warm start pays (a cold first pose costs
/// a few times a warm one), short enough that 10⁵ poses make ~400 chunks for the workers.
pub const DEFAULT_CHUNK_POSES: usize = 256;
/// Most poses per chunk.
pub const MAX_CHUNK_POSES: usize = 1 << 24;

/// The poses and lower tension bounds of one sweep, as flat float64 buffers.
pub struct SweepInput {
    /// Poses.
    n: usize,
    /// Positions, m, n × 3 row-major.
    positions_m: Vec<f64>,
    /// Orientations [w, x, y, z], n × 4 row-major, or empty for the scene's.
    orientations_wxyz: Vec<f64>,
    /// Lower tension bounds, N.
    t_min: TminInput,
}

/// How a sweep's T_min is given.
enum TminInput {
    /// Every cable's own bound from the scene.
    Scene,
    /// One value per pose (every cable), N.
    Uniform(Vec<f64>),
    /// n × cables values, N, row-major.
    PerCable(Vec<f64>),
}

/// What a sweep returns per pose, as flat columns.
#[derive(Default)]
struct Columns {
    status: Vec<u32>,
    tensions_n: Vec<f64>,
    f1_hz: Vec<f64>,
    f1_ee_participation: Vec<f64>,
    ee_mode_hz: Vec<f64>,
    ee_mode_participation: Vec<f64>,
    stiffness_principal_n_m: Vec<f64>,
    t_min_n: Vec<f64>,
    names: BTreeMap<u32, &'static str>,
}

impl Columns {
    fn push(&mut self, e: &Estimate, t_min_n: f64) {
        let code = e.status.as_u32();
        self.status.push(code);
        self.names.entry(code).or_insert(e.status.as_str());
        self.tensions_n.extend_from_slice(e.tensions());
        self.f1_hz.push(e.f1_hz);
        self.f1_ee_participation.push(e.f1_ee_participation);
        self.ee_mode_hz
            .push(e.ee_mode.map_or(f64::NAN, |m| m.frequency_hz));
        self.ee_mode_participation
            .push(e.ee_mode.map_or(f64::NAN, |m| m.participation));
        self.stiffness_principal_n_m
            .extend_from_slice(&principal_stiffness_n_m(e));
        self.t_min_n.push(t_min_n);
    }

    fn append(&mut self, mut o: Columns) {
        self.status.append(&mut o.status);
        self.tensions_n.append(&mut o.tensions_n);
        self.f1_hz.append(&mut o.f1_hz);
        self.f1_ee_participation.append(&mut o.f1_ee_participation);
        self.ee_mode_hz.append(&mut o.ee_mode_hz);
        self.ee_mode_participation
            .append(&mut o.ee_mode_participation);
        self.stiffness_principal_n_m
            .append(&mut o.stiffness_principal_n_m);
        self.t_min_n.append(&mut o.t_min_n);
        self.names.append(&mut o.names);
    }
}

/// The principal values of the static end-effector stiffness (translational block), N/m,
/// ascending: the eigenvalues of (K + Kᵀ)/2 (K is symmetric up to rounding), as the
/// studies' `k_min_n_m` (the first). NaN unless the estimate is ok and K finite.
fn principal_stiffness_n_m(e: &Estimate) -> [f64; 3] {
    let k = e.stiffness.translational_n_m();
    if !e.is_ok() || !k.iter().all(|x| x.is_finite()) {
        return [f64::NAN; 3];
    }
    let sym = (k + k.transpose()) * 0.5;
    let mut v: [f64; 3] = sym.symmetric_eigenvalues().into();
    v.sort_by(f64::total_cmp);
    v
}

/// Evaluate chunk `k` of `input` with `est` (reset to `cold` first).
fn run_chunk(
    est: &mut Estimator,
    cold: &Estimator,
    input: &SweepInput,
    k: usize,
    chunk: usize,
) -> Columns {
    est.clone_from(cold);
    let (a, b) = (k * chunk, ((k + 1) * chunk).min(input.n));
    let n_cables = cold.scene().n_cables();
    let q_scene = cold.scene().ee_orientation_wxyz;
    let mut out = Columns::default();
    for i in a..b {
        let p = &input.positions_m[3 * i..3 * i + 3];
        let orientation_wxyz = if input.orientations_wxyz.is_empty() {
            q_scene
        } else {
            let q = &input.orientations_wxyz[4 * i..4 * i + 4];
            [q[0], q[1], q[2], q[3]]
        };
        let pose = Pose {
            position_m: Vector3::new(p[0], p[1], p[2]),
            orientation_wxyz,
        };
        let t = match &input.t_min {
            TminInput::Scene => Tmin::Scene,
            TminInput::Uniform(v) => Tmin::Uniform(v[i]),
            TminInput::PerCable(v) => Tmin::PerCable(&v[n_cables * i..n_cables * (i + 1)]),
        };
        let e = *est.update(&pose, t);
        out.push(&e, t.lowest_n(est.scene()));
    }
    out
}

/// Evaluate every chunk on `threads` workers (0: one per core), one estimator each.
fn run(cold: &Estimator, input: &SweepInput, threads: usize, chunk: usize) -> PyResult<Columns> {
    let n_chunks = input.n.div_ceil(chunk);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(thread_count(threads))
        .build()
        .map_err(|e| CablevibError::new_err(format!("worker threads: {e}")))?;
    let per_chunk: Vec<Columns> = pool.install(|| {
        (0..n_chunks)
            .into_par_iter()
            .map_init(
                || cold.clone(),
                |est, k| run_chunk(est, cold, input, k, chunk),
            )
            .collect()
    });
    let mut all = Columns::default();
    for c in per_chunk {
        all.append(c);
    }
    Ok(all)
}

/// Worker threads of `threads` (0: one per core; at most `MAX_THREADS`).
fn thread_count(threads: usize) -> usize {
    match threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        t => t.min(MAX_THREADS),
    }
}

/// The numpy module (imported by the package already: a lookup in `sys.modules`).
fn numpy(py: Python<'_>) -> PyResult<Bound<'_, PyModule>> {
    py.import("numpy")
}

/// `obj` as a C-contiguous float64 array: its shape and its values, row-major.
fn f64_array(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    crate::convert::refuse_non_number_sequence(obj, what)?;
    let np = numpy(obj.py())?;
    let a = np
        .call_method1("ascontiguousarray", (obj, "float64"))
        .map_err(|e| PyValueError::new_err(format!("{what}: not an array of numbers ({e})")))?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let raw = a.call_method0("tobytes")?;
    let bytes = raw.cast::<PyBytes>()?.as_bytes();
    let values = bytes
        .chunks_exact(8)
        .map(|c| {
            let mut b = [0u8; 8];
            b.copy_from_slice(c);
            f64::from_ne_bytes(b)
        })
        .collect();
    Ok((shape, values))
}

/// The shape as Python prints it: `(3,)`, `(5, 4)`.
fn shape_text(s: &[usize]) -> String {
    match s {
        [a] => format!("({a},)"),
        _ => format!(
            "({})",
            s.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Check and flatten the arguments of a sweep of a scene with `n_cables` cables.
pub fn input(
    positions: &Bound<'_, PyAny>,
    orientations: Option<&Bound<'_, PyAny>>,
    t_min: Option<&Bound<'_, PyAny>>,
    n_cables: usize,
) -> PyResult<SweepInput> {
    let (s, positions_m) = f64_array(positions, "positions")?;
    let n = match s[..] {
        [n, 3] => n,
        _ => {
            return Err(PyValueError::new_err(format!(
                "positions: expected shape (n, 3) (m), got {}",
                shape_text(&s)
            )))
        }
    };
    let orientations_wxyz = match orientations {
        None => Vec::new(),
        Some(o) => {
            let (s, v) = f64_array(o, "orientations")?;
            if s[..] != [n, 4] {
                return Err(PyValueError::new_err(format!(
                    "orientations: expected shape ({n}, 4) (unit quaternions w, x, y, z), got {}",
                    shape_text(&s)
                )));
            }
            v
        }
    };
    let t_min = match t_min {
        None => TminInput::Scene,
        Some(t) => {
            let (s, v) = f64_array(t, "t_min")?;
            if s[..] == [n] {
                TminInput::Uniform(v)
            } else if s[..] == [n, n_cables] {
                TminInput::PerCable(v)
            } else {
                return Err(PyValueError::new_err(format!(
                    "t_min: expected shape ({n},) or ({n}, {n_cables}) (N), got {}",
                    shape_text(&s)
                )));
            }
        }
    };
    Ok(SweepInput {
        n,
        positions_m,
        orientations_wxyz,
        t_min,
    })
}

/// A numpy array of `shape` and `dtype` holding `values` (copied once, writable).
fn array<'py, T: Copy>(
    py: Python<'py>,
    values: &[T],
    to_bytes: fn(T) -> [u8; 8],
    dtype: &str,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let mut bytes = Vec::with_capacity(8 * values.len());
    for &v in values {
        bytes.extend_from_slice(&to_bytes(v));
    }
    let buf = PyByteArray::new(py, &bytes);
    numpy(py)?
        .call_method1("frombuffer", (buf, dtype))?
        .call_method1("reshape", (shape.to_vec(),))
}

/// Sweep `input` from the cold estimator `cold`; the result as a dict of numpy arrays.
pub fn sweep<'py>(
    py: Python<'py>,
    cold: &Estimator,
    input: SweepInput,
    threads: usize,
    chunk_poses: usize,
) -> PyResult<Bound<'py, PyDict>> {
    if !(1..=MAX_CHUNK_POSES).contains(&chunk_poses) {
        return Err(PyValueError::new_err(format!(
            "chunk_poses {chunk_poses}: must be within 1..={MAX_CHUNK_POSES}"
        )));
    }
    let scene: &Scene = cold.scene();
    let (n, m) = (input.n, scene.n_cables());
    let cols = py.detach(|| run(cold, &input, threads, chunk_poses))?;
    let f8 = |v: f64| v.to_ne_bytes();
    let u8_ = |v: u64| v.to_ne_bytes();
    let d = PyDict::new(py);
    d.set_item(
        "positions_m",
        array(py, &input.positions_m, f8, "float64", &[n, 3])?,
    )?;
    let q: Vec<f64> = if input.orientations_wxyz.is_empty() {
        (0..n).flat_map(|_| scene.ee_orientation_wxyz).collect()
    } else {
        input.orientations_wxyz
    };
    d.set_item("orientations_wxyz", array(py, &q, f8, "float64", &[n, 4])?)?;
    d.set_item("t_min_n", array(py, &cols.t_min_n, f8, "float64", &[n])?)?;
    let codes: Vec<u64> = cols.status.iter().map(|&c| u64::from(c)).collect();
    let code_arr = array(py, &codes, u8_, "uint64", &[n])?;
    d.set_item("status_code", code_arr.call_method1("astype", ("uint32",))?)?;
    let names: BTreeMap<u32, Bound<'_, PyString>> = cols
        .names
        .iter()
        .map(|(&c, &s)| (c, PyString::intern(py, s)))
        .collect();
    let list = PyList::empty(py);
    for c in &cols.status {
        list.append(&names[c])?;
    }
    d.set_item("status", numpy(py)?.call_method1("asarray", (list, "str"))?)?;
    let ok: Vec<u64> = cols.status.iter().map(|&c| u64::from(c == 0)).collect();
    let ok_arr = array(py, &ok, u8_, "uint64", &[n])?;
    d.set_item("ok", ok_arr.call_method1("astype", ("bool",))?)?;
    d.set_item(
        "tensions_n",
        array(py, &cols.tensions_n, f8, "float64", &[n, m])?,
    )?;
    d.set_item("f1_hz", array(py, &cols.f1_hz, f8, "float64", &[n])?)?;
    d.set_item(
        "f1_ee_participation",
        array(py, &cols.f1_ee_participation, f8, "float64", &[n])?,
    )?;
    d.set_item(
        "ee_mode_hz",
        array(py, &cols.ee_mode_hz, f8, "float64", &[n])?,
    )?;
    d.set_item(
        "ee_mode_participation",
        array(py, &cols.ee_mode_participation, f8, "float64", &[n])?,
    )?;
    let k = array(py, &cols.stiffness_principal_n_m, f8, "float64", &[n, 3])?;
    let k_min: Vec<f64> = cols
        .stiffness_principal_n_m
        .iter()
        .step_by(3)
        .copied()
        .collect();
    d.set_item("stiffness_principal_n_m", k)?;
    d.set_item("k_min_n_m", array(py, &k_min, f8, "float64", &[n])?)?;
    d.set_item("threads", thread_count(threads))?;
    d.set_item("chunk_poses", chunk_poses)?;
    Ok(d)
}

/// ``sweep(scene, positions, orientations=None, t_min=None, threads=0, chunk_poses=256)``:
/// ``Estimator(scene).sweep(...)`` (see ``Estimator.sweep``).
#[pyfunction]
#[pyo3(name = "sweep", signature = (scene, positions, orientations = None, t_min = None, threads = 0, chunk_poses = DEFAULT_CHUNK_POSES))]
pub fn sweep_scene<'py>(
    py: Python<'py>,
    scene: &crate::scene::PyScene,
    positions: &Bound<'py, PyAny>,
    orientations: Option<&Bound<'py, PyAny>>,
    t_min: Option<&Bound<'py, PyAny>>,
    threads: usize,
    chunk_poses: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let cold = Estimator::new(&scene.inner).map_err(|e| CablevibError::new_err(e.to_string()))?;
    let inp = input(positions, orientations, t_min, cold.scene().n_cables())?;
    sweep(py, &cold, inp, threads, chunk_poses)
}
