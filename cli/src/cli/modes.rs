//! `cablevib modes`: the lowest natural frequencies of one pose with their mode shapes,
//! from the structured solver (eigenvalues from the spectrum engine, shapes from the
//! chains' closed forms; see [`crate::modal::ModeShapes`]), as a table, a CSV
//! ([`crate::report::shapes_csv`]) and an SVG ([`crate::report::svg::modes`]).

use super::args::{resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::CliError;
use crate::cable::CableModel;
use crate::estimator::{build_models, resolve_auto, Tmin};
use crate::kinematics::{rotation_of, Geometry};
use crate::modal::{self, ModalParams, ModalSolver, Mode, ModeShapes, ShapeParams};
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::shapes_csv::shapes_csv;
use crate::report::svg::modes::modes_svg;
use crate::scene::{ElementKind, Scene};
use clap::Args;
use nalgebra::{DMatrix, Matrix3, Matrix6};
use std::path::PathBuf;
use std::time::Instant;

/// Most modes the command computes.
const MAX_MODES: usize = 1000;

/// `cablevib modes`.
#[derive(Debug, Args)]
pub struct ModesArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Number of modes (lowest first; a cluster cut by the limit is completed), 1..=1000.
    #[arg(long, default_value_t = 6)]
    pub modes: usize,
    /// Points at which a continuous cable is sampled (anchor and end included), 2..=10001.
    #[arg(long, default_value_t = 41)]
    pub samples: usize,
    /// Write the mode shapes as CSV (mass-normalised, 1/√kg).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the mode shapes as a figure (axonometric view, one panel per mode): SVG, or
    /// PNG / PDF by the extension or --format.
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png (3 px per SVG px) or pdf (vector, font embedded). Default:
    /// the figure path's extension, else svg; --format wins and sets the file's extension.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
}

/// One pose's model, as the shapes need it: geometry, tensions (Clarabel reference, N),
/// cable models and the end-effector's mass, inertia and rotational geometric stiffness.
#[derive(Debug, Clone)]
pub struct PoseModel {
    /// The scene (element resolved when it was `auto`).
    pub scene: Scene,
    /// Cable geometry at the scene's pose.
    pub geometry: Geometry,
    /// Tensions, N.
    pub tensions_n: Vec<f64>,
    /// The cable models.
    pub models: Vec<CableModel>,
    /// World-frame inertia about the centroid, kg·m² (rigid body).
    pub inertia_kg_m2: Matrix3<f64>,
    /// Rotational geometric stiffness of the tensions, N·m/rad (rigid body).
    pub k_geo_rot: Matrix3<f64>,
}

impl PoseModel {
    /// The model of `scene` at its own pose (`ee_position_m`, `ee_orientation_wxyz`) and
    /// each cable's own lower bound (`Tmin::Scene`), with the tensions of the Clarabel
    /// reference.
    pub fn new(scene: &Scene) -> Result<PoseModel, CliError> {
        let scene = if scene.model.element == ElementKind::Auto {
            resolve_auto(scene)
                .map_err(|e| CliError::Analysis(e.to_string()))?
                .0
        } else {
            scene.clone()
        };
        let n = scene.n_cables();
        let mut geometry = Geometry::new(n);
        let rot = rotation_of(&scene.ee_orientation_wxyz);
        let anchors = scene.cables.iter().map(|c| &c.anchor_m);
        let r = if scene.rigid {
            let att = scene.cables.iter().map(|c| &c.attachment_m);
            geometry.update_rigid(anchors, att, &scene.ee_position_m, &rot)
        } else {
            geometry.update(anchors, &scene.ee_position_m)
        };
        r.map_err(|e| CliError::Analysis(e.to_string()))?;
        let w = scene.wrench_n();
        let t_max: Vec<f64> = (0..n).map(|i| scene.cable_t_max_n(i)).collect();
        let t_min = Tmin::Scene.per_cable(&scene);
        let tensions_n = crate::tension::clarabel_reference_bounds(
            &geometry,
            &[w.x, w.y, w.z, 0.0, 0.0, 0.0],
            &t_min[..n],
            &t_max,
        )
        .map_err(|e| CliError::Analysis(e.to_string()))?;
        let models = build_models(&scene, &geometry, &tensions_n)
            .map_err(|e| CliError::Analysis(e.to_string()))?;
        let inertia_kg_m2 = rot * scene.ee_inertia_kg_m2 * rot.transpose();
        let k_geo_rot =
            modal::rigid_geometric_stiffness(&geometry.unit, &geometry.arm_m, &tensions_n);
        Ok(PoseModel {
            scene,
            geometry,
            tensions_n,
            models,
            inertia_kg_m2,
            k_geo_rot,
        })
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        if self.scene.rigid {
            6
        } else {
            3
        }
    }

    /// Load `solver` with this pose.
    pub fn load(&self, solver: &mut ModalSolver) {
        if self.scene.rigid {
            solver.load_rigid(
                &self.models,
                self.scene.ee_mass_kg,
                &self.inertia_kg_m2,
                &self.geometry.arm_m,
                &self.k_geo_rot,
            );
        } else {
            solver.load(&self.models, self.scene.ee_mass_kg);
        }
    }

    /// The end-effector's own mass matrix (its leading `dim` block), kg and kg·m².
    pub fn ee_mass(&self) -> Matrix6<f64> {
        let mut m = Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * self.scene.ee_mass_kg));
        if self.scene.rigid {
            m.fixed_view_mut::<3, 3>(3, 3)
                .copy_from(&self.inertia_kg_m2);
        }
        m
    }

    /// The dense K and M (not for continuous cables).
    pub fn dense(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), modal::ModalError> {
        if self.scene.rigid {
            modal::assemble_rigid(
                &self.models,
                self.scene.ee_mass_kg,
                &self.inertia_kg_m2,
                &self.geometry.arm_m,
                &self.k_geo_rot,
            )
        } else {
            modal::assemble(&self.models, self.scene.ee_mass_kg)
        }
    }

    /// The lowest `k` modes' shapes (clusters completed) from the structured solver.
    pub fn shapes(&self, k: usize, params: &ShapeParams) -> Result<ModeShapes, CliError> {
        let mut solver = ModalSolver::new(ModalParams::default());
        self.load(&mut solver);
        let err = |e: modal::ShapeError| CliError::Analysis(e.to_string());
        let clusters = lowest_clusters(&mut solver, k)?;
        solver
            .mode_shapes(&self.models, &self.geometry.arm_m, &clusters, params)
            .map_err(err)
    }
}

/// The lowest clusters (λ, multiplicity) covering at least `k` modes, from the spectrum
/// engine ([`ModalSolver::modes`]); a cluster cut by `k` is completed.
fn lowest_clusters(solver: &mut ModalSolver, k: usize) -> Result<Vec<(f64, u32)>, CliError> {
    let mut modes = vec![Mode::default(); k + modal::MAX_MULTIPLICITY as usize];
    let n = solver
        .modes(modes.len(), &mut modes)
        .map_err(|e| CliError::Analysis(e.to_string()))?;
    let mut out = Vec::new();
    let mut covered = 0usize;
    for (i, m) in modes[..n].iter().enumerate() {
        if covered >= k {
            break;
        }
        if m.cluster_start == i {
            out.push((m.lambda, m.multiplicity));
            covered += m.multiplicity as usize;
        }
    }
    Ok(out)
}

/// `cablevib modes`.
pub fn run(a: &ModesArgs) -> Result<(), CliError> {
    if !(1..=MAX_MODES).contains(&a.modes) {
        return Err(CliError::Usage(format!(
            "--modes {}: must be in 1..={MAX_MODES}",
            a.modes
        )));
    }
    let params = ShapeParams {
        continuous_samples: a.samples,
        ..ShapeParams::default()
    };
    params
        .check()
        .map_err(|e| CliError::Usage(format!("--samples {}: {e}", a.samples)))?;
    let s = resolve_scene(&a.scene)?;
    let pose = PoseModel::new(&s)?;
    let t0 = Instant::now();
    let shapes = pose.shapes(a.modes, &params)?;
    let secs = t0.elapsed().as_secs_f64();
    let sc = &pose.scene;
    let p = sc.ee_position_m;
    println!(
        "scene {}  position ({:.4}, {:.4}, {:.4}) m  T_min {}  model {} × {}  ({} modes with shapes in {:.1} ms)",
        sc.name,
        p.x,
        p.y,
        p.z,
        sc.t_min_label(),
        sc.model.element.as_str(),
        sc.model.elements_per_cable,
        shapes.modes.len(),
        secs * 1e3
    );
    println!("\n mode   frequency (Hz)   multiplicity   end-effector participation");
    for (i, m) in shapes.modes.iter().enumerate() {
        println!(
            " {:>4}   {:>14.6}   {:>12}   {:>8.4}",
            i + 1,
            m.frequency_hz,
            m.multiplicity,
            m.ee_participation
        );
    }
    if let Some(path) = &a.csv {
        write_csv(
            path,
            shapes_csv(sc, &pose.geometry, &shapes),
            &process_command_line(),
        )?;
        println!("\nwrote {}", path.display());
    }
    if a.format.is_some() && a.svg.is_none() {
        let msg = "--format needs --svg PATH (the figure is written only there)";
        return Err(CliError::Usage(msg.into()));
    }
    if let Some(path) = &a.svg {
        let (path, fmt) = figure::target(path, a.format)?;
        let k = a.modes.min(shapes.modes.len());
        figure::write(&path, &modes_svg(sc, &pose.geometry, &shapes, k), fmt)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
