//! [`Scene::load`]: a scene file, or one of the embedded scenes by name.

use super::{Scene, SceneError};
use std::path::Path;

/// The names [`Scene::load`] accepts for the embedded scenes (when no file of that name
/// exists), as listed in its error message.
pub(super) const EMBEDDED_NAMES: [&str; 7] = [
    "spatial-paper",
    "spatial",
    "default",
    "planar-paper",
    "planar",
    "fast-like",
    "suspended-8",
];

/// The large suspended robot in the spirit of FAST's feed support (sagging cables).
const FAST_LIKE_TOML: &str = include_str!("../../scenes/fast_like.toml");
/// The 15 × 11 × 6 m suspended 8-cable robot (sagging cables).
const SUSPENDED_8_TOML: &str = include_str!("../../scenes/suspended_8.toml");

impl Scene {
    /// The TOML text and origin of the embedded scene of name `name` (`spatial-paper`,
    /// `spatial`, `default`, `planar-paper`, `planar`, `fast-like`, `suspended-8`; see
    /// [`Scene::load`]); `None` for any other name.
    fn builtin_text(name: &str) -> Option<(&'static str, &'static str)> {
        match name {
            "spatial-paper" | "spatial" | "default" => {
                Some((super::DEFAULT_SCENE_TOML, "<embedded spatial_paper.toml>"))
            }
            "planar-paper" | "planar" => {
                Some((super::PLANAR_SCENE_TOML, "<embedded planar_paper.toml>"))
            }
            "fast-like" => Some((FAST_LIKE_TOML, "<embedded fast_like.toml>")),
            "suspended-8" => Some((SUSPENDED_8_TOML, "<embedded suspended_8.toml>")),
            _ => None,
        }
    }

    /// The embedded scene of name `name` (see [`Scene::load`]), without looking at files;
    /// `None` for any other name.
    pub fn builtin(name: &str) -> Option<Result<Scene, SceneError>> {
        Self::builtin_text(name).map(|(text, origin)| Scene::from_toml_str(text, origin))
    }

    /// Load a scene by path or by name: `name_or_path` is read as a scene file when it
    /// exists; otherwise `spatial-paper` (also `spatial`, `default`) is the embedded
    /// [`Scene::default_scene`] and `planar-paper` (also `planar`) the embedded
    /// [`Scene::planar_paper`]; `fast-like` and `suspended-8` are scenes/fast_like.toml and
    /// scenes/suspended_8.toml (the sagging-cable robots). Anything else is
    /// [`SceneError::NotFound`]; a file that exists but cannot be read or validated gives
    /// that error.
    ///
    /// ```
    /// use cablevib::scene::Scene;
    ///
    /// let s = Scene::load("spatial-paper")?; // or a path to a scene .toml
    /// assert_eq!(s.n_cables(), 8);
    /// assert!(Scene::load("no-such-robot").is_err());
    /// # Ok::<(), cablevib::scene::SceneError>(())
    /// ```
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        let (text, origin) = Self::source_text(name_or_path)?;
        Scene::from_toml_str(&text, &origin)
    }

    /// The TOML text [`Scene::load`] reads for `name_or_path` and the name its messages
    /// give it: a file's (a regular file of at most [`super::MAX_SCENE_BYTES`]) or an
    /// embedded scene's. What a writer of a changed copy of the scene starts from
    /// (`cablevib calibrate -o`).
    pub fn source_text(name_or_path: &str) -> Result<(String, String), SceneError> {
        let p = Path::new(name_or_path);
        let exists = p.try_exists();
        if !matches!(exists, Ok(true)) {
            if let Some((text, origin)) = Self::builtin_text(name_or_path) {
                return Ok((text.to_string(), origin.to_string()));
            }
            // Known absent (not, e.g., an unreadable directory: that reports its reason).
            if matches!(exists, Ok(false)) {
                return Err(SceneError::NotFound {
                    name: name_or_path.to_string(),
                });
            }
        }
        let text = crate::input_file::read_text(p, "scene file", super::MAX_SCENE_BYTES)?;
        Ok((text, p.display().to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_names() {
        for name in ["spatial-paper", "spatial", "default"] {
            assert_eq!(Scene::load(name).unwrap(), Scene::default_scene(), "{name}");
        }
        for name in ["planar-paper", "planar"] {
            assert_eq!(Scene::load(name).unwrap(), Scene::planar_paper(), "{name}");
        }
        for (name, file) in [("fast-like", "fast_like"), ("suspended-8", "suspended_8")] {
            let path = format!("{}/scenes/{file}.toml", env!("CARGO_MANIFEST_DIR"));
            let from_file = Scene::load(&path).unwrap();
            assert_eq!(Scene::load(name).unwrap(), from_file, "{name}");
            assert_eq!(from_file.name, name);
        }
    }

    #[test]
    fn a_path_is_read() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/box_6dof.toml");
        assert_eq!(Scene::load(path).unwrap(), Scene::box_6dof());
    }

    #[test]
    fn a_file_wins_over_an_embedded_name() {
        let dir = std::env::temp_dir().join(format!("cablevib-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("planar");
        std::fs::write(&file, super::super::BOX_SCENE_TOML).unwrap();
        let s = Scene::load(file.to_str().unwrap());
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(s.unwrap().n_cables(), Scene::box_6dof().n_cables());
    }

    #[test]
    fn an_unknown_name_is_a_clear_error() {
        let e = Scene::load("no-such-scene.toml").unwrap_err();
        assert!(matches!(e, SceneError::NotFound { .. }), "{e:?}");
        let msg = e.to_string();
        assert!(
            msg.starts_with("no-such-scene.toml: no such scene file"),
            "{msg}"
        );
        assert!(
            msg.contains("spatial-paper") && msg.contains("planar-paper"),
            "{msg}"
        );
    }

    #[test]
    fn a_bad_file_names_file_and_key() {
        let dir = std::env::temp_dir().join(format!("cablevib-load-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("bad.toml");
        let text = super::super::DEFAULT_SCENE_TOML.replace("mass = 30.0", "mass = -1.0");
        std::fs::write(&file, text).unwrap();
        let e = Scene::load(file.to_str().unwrap()).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            e.contains("bad.toml") && e.contains("end_effector.mass"),
            "{e}"
        );
    }

    /// `Scene::load` of `path` in a thread, failing the test if it blocks.
    fn load_within_timeout(path: &Path) -> Result<Scene, SceneError> {
        let p = path.to_str().expect("UTF-8 path").to_string();
        crate::input_file::test_files::within_timeout(move || Scene::load(&p))
    }

    #[test]
    fn devices_fifos_and_directories_are_refused_without_blocking() {
        use crate::input_file::test_files::{non_regular, temp_dir};
        let dir = temp_dir("scene-kinds");
        for (p, kind) in non_regular(&dir, "scene.toml") {
            let msg = load_within_timeout(&p).unwrap_err().to_string();
            let name = p.display().to_string();
            assert!(
                msg.starts_with(&format!("{name}: is a {kind}")) && msg.contains("scene file"),
                "{msg}"
            );
            assert!(!msg.contains('\n'), "{msg}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_scene_file_over_the_limit_is_refused() {
        use crate::input_file::test_files::{sparse, temp_dir};
        use crate::input_file::MAX_SCENE_BYTES;
        let dir = temp_dir("scene-size");
        let big = sparse(&dir, "big.toml", MAX_SCENE_BYTES + 1);
        let msg = load_within_timeout(&big).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        let expected = format!(
            "{}: scene file is {} bytes, over the limit of {MAX_SCENE_BYTES} bytes",
            big.display(),
            MAX_SCENE_BYTES + 1
        );
        assert_eq!(msg, expected);
    }

    #[test]
    fn a_non_utf8_scene_file_is_refused() {
        let dir = crate::input_file::test_files::temp_dir("scene-utf8");
        let file = dir.join("latin1.toml");
        std::fs::write(&file, b"name = \"caf\xe9\"\n").unwrap();
        let msg = load_within_timeout(&file).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            msg.contains("latin1.toml")
                && msg.contains("not UTF-8 text (invalid byte at offset 11)"),
            "{msg}"
        );
    }

    #[test]
    fn a_toml_error_is_one_line_under_the_file_name() {
        let e = Scene::from_toml_str("name = \"x\"\ngravity = [0, 0\n", "s.toml")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "s.toml: line 2, column 16: key `gravity`: unclosed array, expected `]`"
        );
    }
}
