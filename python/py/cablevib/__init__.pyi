"""cablevib: tension distribution, stiffness and natural frequencies of cable-driven
parallel robots (Python bindings of the Rust crate). SI units: m, kg, N, N/m, Hz."""

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Vec = Union[Sequence[float], npt.NDArray[np.floating[Any]]]
_F64 = npt.NDArray[np.float64]
_Arr = Union[Sequence[Sequence[float]], npt.NDArray[np.floating[Any]]]

class CablevibError(ValueError):
    """An error of cablevib, with the command line's one-line message."""

class Scene:
    """A validated robot description (SI units), read-only."""

    @staticmethod
    def load(path_or_name: Union[str, "os.PathLike[str]"]) -> "Scene":
        """A scene TOML file, or an embedded name: ``spatial-paper``, ``planar-paper``."""
    @staticmethod
    def from_toml(text: str, source: str = "<string>") -> "Scene":
        """Parse a scene from TOML text; ``source`` names it in error messages."""
    @staticmethod
    def from_arrays(
        anchors_m: _Arr,
        ee_mass_kg: float,
        ee_position_m: _Vec,
        *,
        attachments_m: Optional[_Arr] = None,
        name: str = "from-arrays",
        gravity_m_s2: Optional[_Vec] = None,
        ee_orientation_wxyz: Optional[_Vec] = None,
        ee_inertia_kg_m2: Optional[_Arr] = None,
        weight_carried: Optional[bool] = None,
        youngs_modulus_pa: Union[None, float, _Vec] = None,
        area_m2: Union[None, float, _Vec] = None,
        weight_per_length_n_m: Union[None, float, _Vec] = None,
        mass_per_length_kg_m: Union[None, float, _Vec] = None,
        t_min_n: Optional[float] = None,
        t_max_n: Optional[float] = None,
        cable_t_min_n: Optional[_Vec] = None,
        cable_t_max_n: Optional[_Vec] = None,
        element: str = "fem",
        elements: Optional[int] = None,
        ee_participation_min: Optional[float] = None,
        f1_tolerance: Optional[float] = None,
        sag: Optional[bool] = None,
        rotation: Optional[bool] = None,
        geometric_stiffness: Optional[bool] = None,
        cable_mass: Optional[bool] = None,
        source: str = "<arrays>",
    ) -> "Scene":
        """A scene from arrays (m, kg, Pa, m², N/m, kg/m, N), written as a scene file's TOML
        text and validated as one: a bad value raises the scene file's error. Material
        given as one number is every cable's, as n numbers one per cable."""
    @property
    def toml(self) -> Optional[str]:
        """The TOML text the scene was read from (None for an embedded scene by name);
        a scene pickles by it (or by its embedded name)."""
    @property
    def name(self) -> str: ...
    @property
    def n_cables(self) -> int: ...
    @property
    def element(self) -> str:
        """``fem``, ``catenary``, ``continuous``, ``massless`` or ``auto``."""
    @property
    def elements(self) -> int:
        """Elements per cable."""
    @property
    def t_min_n(self) -> float:
        """Lower tension bound, N."""
    @property
    def t_max_n(self) -> float:
        """Upper tension bound, N."""
    @property
    def cable_t_min_n(self) -> _F64:
        """Each cable's lower bound, N, shape (n_cables,)."""
    @property
    def cable_t_max_n(self) -> _F64:
        """Each cable's upper bound, N, shape (n_cables,)."""
    @property
    def ee_position_m(self) -> _F64:
        """Default end-effector position, m, shape (3,)."""
    @property
    def ee_orientation_wxyz(self) -> _F64:
        """Default orientation, unit quaternion [w, x, y, z], shape (4,)."""
    @property
    def ee_mass_kg(self) -> float: ...
    @property
    def gravity_m_s2(self) -> _F64:
        """Gravity vector, m/s², shape (3,)."""
    @property
    def weight_carried(self) -> bool: ...
    @property
    def rigid(self) -> bool:
        """Rigid-body end-effector (6 DOF) rather than a point mass."""
    @property
    def anchors_m(self) -> _F64:
        """Cable anchors, m, shape (n_cables, 3)."""
    @property
    def ee_participation_min(self) -> float: ...
    @property
    def f1_tolerance(self) -> float: ...

def analyze(
    scene: Scene,
    position: Optional[_Vec] = None,
    t_min: Optional[float] = None,
    element: Optional[str] = None,
    elements: Optional[int] = None,
    modes: int = 10,
    solver: str = "structured",
    compare_dense: bool = False,
    orientation: Optional[_Vec] = None,
    sag: Optional[bool] = None,
) -> Dict[str, Any]:
    """What ``cablevib analyze SCENE --json`` prints, as a dict with numpy arrays:
    ``scene``, ``position_m`` (m), ``orientation_wxyz`` (unit quaternion), ``t_min_n`` (N),
    ``tensions_n`` (N), ``frequencies_hz`` (Hz), ``ee_participation``, ``multiplicity``,
    ``cluster_start``, ``dof``, ``element``, ``elements_per_cable``, ``stiffness_n_m``
    (3 × 3, N/m, for a point mass; 6 × 6 for a rigid end-effector over x, y, z, θx, θy, θz:
    blocks N/m, N/rad, N·m/m, N·m/rad), ``solver``, ``solve_seconds``,
    ``dense_seconds``, ``compare_dense``, ``sag``; with sagging cables also
    ``tensions_anchor_n``, ``tensions_min_n`` (N), ``sag_m`` (m), ``irvine_lambda2`` and
    ``unstretched_length_m`` (m), one per cable. Overrides as ``--position`` (m),
    ``--orientation`` (unit quaternion w, x, y, z; rigid end-effectors only), ``--t-min`` (N),
    ``--element``, ``--elements``, ``--sag``; ``solver`` is ``structured`` or ``dense``."""

def frf(
    scene: Scene,
    from_hz: float = 0.5,
    to_hz: float = 50.0,
    points: int = 1000,
    log: bool = False,
    position: Optional[_Vec] = None,
    t_min: Optional[float] = None,
    element: Optional[str] = None,
    elements: Optional[int] = None,
    loss_factor: Optional[float] = None,
    rayleigh: Optional[Tuple[float, float]] = None,
    modal_ratio: Optional[float] = None,
    undamped: bool = False,
) -> Dict[str, Any]:
    """What ``cablevib frf SCENE --json`` prints, from the same library function:
    ``frequencies_hz`` (N,), ``receptance_re``, ``receptance_im`` (float64 numpy arrays of
    shape (N, d, d), m/N; d = 3, or 6 for a rigid end-effector, translations first),
    ``natural_frequencies_hz`` (the band's natural frequencies whose modes move the
    end-effector, Hz), ``damping`` (str), ``dim`` (int). Damping: the scene's, or one of
    ``loss_factor`` (η), ``rayleigh`` ((α 1/s, β s)), ``modal_ratio`` (ζ), ``undamped``.
    With sag on, the sagged FEM chains at the pose's sagged tensions (modal damping by
    superposition of the sagged shapes; ``element="continuous"`` refused), as on the
    command line."""

def simulate(
    scene: Scene,
    csv: Union[None, str, "os.PathLike[str]"] = None,
    move: Optional[_Vec] = None,
    duration: float = 0.5,
    profile: str = "s-curve",
    dt: float = 1e-3,
    modal_ratio: Optional[float] = None,
    max_acceleration: float = 200.0,
    circle_s: float = 10.0,
    period_s: float = 4.0,
    modes: Optional[int] = None,
    update_every: Optional[int] = None,
    tolerance: float = 1e-3,
    settle: float = 2.0,
    shaper: str = "none",
    mode: str = "ee",
    position: Optional[_Vec] = None,
    t_min: Optional[float] = None,
    element: Optional[str] = None,
    elements: Optional[int] = None,
    sag: Optional[bool] = None,
) -> Dict[str, Any]:
    """What ``cablevib simulate SCENE`` writes to its CSV (one shaper), as numpy arrays:
    ``t_s`` (N, s), ``deviation_m`` (N × 3, the end-effector's deviation from its
    quasi-static pose, m), ``command_m`` (N × 3, the commanded path, shaped when ``shaper``
    is given, m), ``time_added_s``, ``modes``, ``updates``, ``structured``,
    ``f1_range_hz``, ``accuracy`` (dict), ``stops`` (the residual after each stop), ``path``.
    The path: ``csv``, else ``move`` ((dx, dy, dz) m in ``duration`` s, ``profile``
    ``"s-curve"`` or ``"trapezoid"``), else the paper's circle for ``circle_s`` s; the other
    arguments as the command line's options of the same names."""

def shape(
    scene: Scene,
    trajectory: Union[None, str, "os.PathLike[str]"] = None,
    move: Optional[_Vec] = None,
    duration: float = 0.5,
    profile: str = "s-curve",
    dt: float = 1e-3,
    modal_ratio: Optional[float] = None,
    max_acceleration: float = 200.0,
    shaper: str = "zv",
    mode: str = "ee",
) -> Dict[str, Any]:
    """What ``cablevib shape`` writes to its CSV, as numpy arrays: ``t_s`` (N, s),
    ``path_m`` (N × 3, the shaped positions, m), ``design_hz`` (N, the shaper's design
    frequency at each sample), ``time_added_s``, ``path``. The path: ``trajectory`` (a CSV
    t,x,y,z), else ``move``; ``shaper`` ``"zv"``, ``"zvd"`` or ``"ei"`` following ``mode``
    ``"ee"`` (the end-effector mode) or ``"f1"``."""

def calibrate(
    scene: Scene,
    measurements: Union[str, "os.PathLike[str]"],
    fit: List[str],
    tensions: Union[None, str, "os.PathLike[str]"] = None,
    sigma_rel: float = 0.005,
    damping_sigma_rel: float = 0.2,
    tension_sigma_rel: float = 0.02,
    bounds: Optional[Dict[str, Tuple[float, float]]] = None,
    nominal: Optional[Dict[str, float]] = None,
    prior: Optional[Dict[str, float]] = None,
) -> Dict[str, Any]:
    """What ``cablevib calibrate SCENE --data MEASUREMENTS --fit ... --json`` prints:
    ``parameters`` (``name``, ``value``, ``std_error`` (None when undetermined),
    ``determined``, ``unit``, ``nominal``, bounds, ``sensitivity``), ``correlation``,
    ``singular_values``, ``undetermined``, ``chi2_per_dof``, ``fits``, ``verdict``,
    ``residuals`` (each measured mode before and after), ``left_out``, ``unused_columns``.
    ``measurements``: the modes CSV (``cablevib identify``'s as it is); ``tensions``: the
    tensions CSV; ``bounds``, ``nominal``, ``prior`` by parameter or group name (SI units)."""
def identify(
    t: _Arr,
    channels: _Arr,
    from_hz: float = 0.5,
    to_hz: float = 50.0,
    max_order: int = 60,
    block_rows: Optional[int] = None,
    frequency_tol: float = 0.01,
    damping_tol: float = 0.05,
    mac_min: float = 0.98,
    max_damping: float = 0.2,
    window: Optional[float] = None,
    overlap: float = 0.5,
    inputs: Optional[_Arr] = None,
) -> Dict[str, Any]:
    """Modal identification (SSI-cov; with ``inputs``, measured forces N × m or N, H1 and its
    modal fit, as ``--input``) of ``t`` (N, s) and ``channels`` (N × l or N): what
    ``cablevib identify --json`` prints per window without the model: ``{"windows":
    [{"t_start_s", "t_end_s", "status", "modes": [{"frequency_hz", "damping_ratio",
    "frequency_std_hz", "damping_ratio_std", "shape_re", "shape_im", ...}]}]}``, modes
    ascending. Raises CablevibError on a bad record or parameter."""

def sweep(
    scene: Scene,
    positions: _Arr,
    orientations: Optional[_Arr] = None,
    t_min: Union[None, _Vec, _Arr] = None,
    threads: int = 0,
    chunk_poses: int = 256,
) -> Dict[str, Any]:
    """``Estimator(scene).sweep(...)``."""

class Estimate:
    """One ``Estimator.update``: valid numbers only when ``ok``."""

    @property
    def status(self) -> str:
        """``ok``, ``tension_infeasible``, ``invalid_input``, ``outside_workspace``, …"""
    @property
    def status_code(self) -> int:
        """The service's wire code (0 is ok)."""
    @property
    def ok(self) -> bool: ...
    @property
    def error(self) -> Optional[str]:
        """Why the status is not ok (the command line's message)."""
    @property
    def tensions_n(self) -> _F64:
        """Cable tensions, N, shape (n_cables,)."""
    @property
    def f1_hz(self) -> float:
        """First natural frequency, Hz (NaN unless ok)."""
    @property
    def f1_ee_participation(self) -> float: ...
    @property
    def ee_mode_hz(self) -> float:
        """Lowest mode with end-effector participation ≥ the scene's threshold, Hz."""
    @property
    def ee_mode_participation(self) -> float: ...
    @property
    def ee_mode_age_cycles(self) -> Optional[int]:
        """Cycles since the end-effector mode answer was computed (0: this pose); None if unknown."""
    @property
    def stiffness_n_m(self) -> _F64:
        """Static end-effector stiffness, translational block, N/m, shape (3, 3)."""
    @property
    def stiffness(self) -> _F64:
        """(3, 3) N/m for a point mass, (6, 6) for a rigid body (N/m, N/rad, N·m/rad)."""
    @property
    def eigen_evaluations(self) -> int: ...
    @property
    def eigen_residual(self) -> float: ...
    @property
    def cold_start(self) -> bool: ...
    @property
    def tension_iterations(self) -> int: ...
    @property
    def tension_warm(self) -> bool: ...
    def to_dict(self) -> Dict[str, Any]:
        """Every attribute in a dict (one row of a sweep's table)."""

class TminAnswer:
    """The answer of ``Estimator.t_min_for_f1``."""

    @property
    def t_min_n(self) -> float:
        """The smallest T_min found, N."""
    @property
    def f1_hz(self) -> float:
        """f1 at that T_min, Hz."""
    @property
    def evaluations(self) -> int: ...
    @property
    def resolution_n(self) -> float:
        """The scan step, N: the answer is the smallest T_min at this resolution."""

class Estimator:
    """The real-time estimator of one scene, warm-started from call to call."""

    def __init__(self, scene: Scene, realtime: bool = False) -> None:
        """``realtime=True``: each update as the service runs it (a budget of D(λ)
        evaluations per call; the end-effector mode of a cold call may be pending), what
        ``cablevib analyze --realtime`` prints. Default: every call answered in full."""
    def update(
        self,
        position: _Vec,
        orientation: Optional[_Vec] = None,
        t_min: Union[None, float, _Vec] = None,
    ) -> Estimate:
        """Position (m), orientation [w, x, y, z] (default the scene's), T_min (N: one
        value or one per cable; default the scene's)."""
    def t_min_for_f1(
        self, position: _Vec, required_f1_hz: float, orientation: Optional[_Vec] = None
    ) -> TminAnswer:
        """The smallest T_min (N) for which f1 at ``position`` (m) reaches
        ``required_f1_hz`` (Hz)."""
    def sweep(
        self,
        positions: _Arr,
        orientations: Optional[_Arr] = None,
        t_min: Union[None, _Vec, _Arr] = None,
        threads: int = 0,
        chunk_poses: int = 256,
    ) -> Dict[str, Any]:
        """Many poses in one call, the GIL released, on ``threads`` workers (0: one per
        core): positions (n, 3) m, orientations (n, 4), t_min (n,) or (n, n_cables) N. A dict
        of numpy arrays, one row per pose: ``positions_m``, ``orientations_wxyz``,
        ``t_min_n``, ``status_code``, ``status``, ``ok``, ``tensions_n`` (n, n_cables),
        ``f1_hz``, ``f1_ee_participation``, ``ee_mode_hz``, ``ee_mode_participation``,
        ``stiffness_principal_n_m`` (n, 3, ascending, N/m), ``k_min_n_m``; and ``threads``,
        ``chunk_poses``. Bit for bit the loop ``for each chunk of chunk_poses poses:
        e = Estimator(scene); e.update(...) pose by pose``, for any thread count."""
    def reset(self) -> None: ...
    @property
    def scene(self) -> Scene: ...
    @property
    def auto_choice(self) -> Optional[str]: ...
