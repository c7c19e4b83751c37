//! The checks shared by the 2D and 3D scene validators: every problem names the
//! JSON path of its field and what is wrong.

use crate::core::color::Color;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: cannot read the scene: {message}")]
    Io { file: String, message: String },
    #[error("{file}: {}", format_problems(.problems))]
    Invalid { file: String, problems: Vec<Problem> },
}

fn format_problems(p: &[Problem]) -> String {
    p.iter()
        .map(|p| format!("{}: {}", p.path, p.message))
        .collect::<Vec<_>>()
        .join("; ")
}

impl SceneError {
    pub fn problems(&self) -> &[Problem] {
        match self {
            SceneError::Invalid { problems, .. } => problems,
            SceneError::Io { .. } => &[],
        }
    }
}

/// The text of a scene file (an error names the file).
pub fn read(path: &std::path::Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    })
}

/// Parse scene JSON (unknown fields rejected by the description's serde attributes)
/// and validate it with `validate`; errors name `file` and the JSON path.
pub fn parse<T: serde::de::DeserializeOwned>(
    text: &str,
    file: &str,
    validate: impl FnOnce(&T) -> Vec<Problem>,
) -> Result<T, SceneError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let desc: T = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let problems = vec![Problem {
            path: if path == "." { "(document)".into() } else { path },
            message: e.inner().to_string(),
        }];
        SceneError::Invalid {
            file: file.to_string(),
            problems,
        }
    })?;
    validated(desc, file, validate)
}

/// `desc` if `validate` finds no problem, else an error naming `file`.
pub fn validated<T>(desc: T, file: &str, validate: impl FnOnce(&T) -> Vec<Problem>) -> Result<T, SceneError> {
    match validate(&desc) {
        problems if problems.is_empty() => Ok(desc),
        problems => Err(SceneError::Invalid {
            file: file.to_string(),
            problems,
        }),
    }
}

/// One problem with a scene: the JSON path of the field and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    pub path: String,
    pub message: String,
}

/// Collects problems while a validator walks a scene description.
#[derive(Default)]
pub struct Checker {
    pub problems: Vec<Problem>,
}

impl Checker {
    pub fn fail(&mut self, path: impl Into<String>, message: impl Into<String>) {
        self.problems.push(Problem {
            path: path.into(),
            message: message.into(),
        });
    }

    pub fn finite(&mut self, path: &str, v: f64) -> bool {
        if !v.is_finite() {
            self.fail(path, format!("must be a finite number, got {v}"));
        }
        v.is_finite()
    }

    /// Every coordinate finite (each bad one reported with its index).
    pub fn point<const N: usize>(&mut self, path: &str, p: [f64; N]) -> bool {
        (0..N).fold(true, |ok, k| self.finite(&format!("{path}[{k}]"), p[k]) & ok)
    }

    /// Finite and not the zero vector.
    pub fn nonzero<const N: usize>(&mut self, path: &str, p: [f64; N]) -> bool {
        if self.point(path, p) && p == [0.0; N] {
            self.fail(path, "must not be the zero vector");
            return false;
        }
        true
    }

    /// A colour: finite, not negative, at most `max` when given.
    pub fn color(&mut self, path: &str, c: &Color, max: Option<f64>) {
        for (i, &v) in c.0.iter().enumerate() {
            let p = format!("{path}[{i}]");
            if !self.finite(&p, v) {
                continue;
            }
            if v < 0.0 {
                self.fail(p, format!("must not be negative, got {v}"));
            } else if let Some(m) = max.filter(|&m| v > m) {
                self.fail(p, format!("must be at most {m}, got {v}"));
            }
        }
    }

    /// An axis-aligned box `{path}.min`–`{path}.max` with min < max in every coordinate.
    pub fn bounds<const N: usize>(&mut self, path: &str, min: [f64; N], max: [f64; N]) -> bool {
        let ok = self.point(&format!("{path}.min"), min) & self.point(&format!("{path}.max"), max);
        if ok && !(0..N).all(|k| min[k] < max[k]) {
            self.fail(format!("{path}.max"), "must be greater than min in every coordinate");
            return false;
        }
        ok
    }

    /// Henyey–Greenstein g strictly inside (−1, 1).
    pub fn hg_g(&mut self, path: &str, g: f64) {
        if self.finite(path, g) && !(g > -1.0 && g < 1.0) {
            self.fail(path, format!("must lie strictly between -1 and 1, got {g}"));
        }
    }

    /// The common fields of a `render` block.
    pub fn render_block(&mut self, resolution: [u32; 2], spp: u32, max_depth: u32, exposure: f64) {
        if resolution[0] == 0 || resolution[1] == 0 || resolution[0] > 16384 || resolution[1] > 16384 {
            self.fail(
                "render.resolution",
                format!("must be between 1 and 16384 pixels per side, got {resolution:?}"),
            );
        }
        if spp == 0 {
            self.fail("render.spp", "must be at least 1");
        }
        if max_depth == 0 {
            self.fail("render.max_depth", "must be at least 1");
        }
        self.finite("render.exposure", exposure);
    }
}
