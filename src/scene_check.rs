//! The checks shared by the 2D and 3D scene validators: every problem names the
//! JSON path of its field and what is wrong. The ranges are [`crate::limits`].

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

/// Whether scene JSON is a 3D scene: it parses and has a `camera` block (a 2D
/// scene has none). Anything else is read as 2D, whose loader names the problem.
pub fn is_3d_json(text: &str) -> bool {
    serde_json::from_str::<serde_json::Value>(text).is_ok_and(|v| v.get("camera").is_some())
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
use crate::limits::{self, MAX_COORD, zero_or_within};

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

/// A number as messages show it: plain when short, else in scientific notation.
pub fn shown(v: f64) -> String {
    if v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Euclidean length, computed without overflow or underflow for finite input.
pub fn length<const N: usize>(v: [f64; N]) -> f64 {
    let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * v.iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt()
}

/// Distance between two points (see [`length`]).
pub fn distance<const N: usize>(a: [f64; N], b: [f64; N]) -> f64 {
    length(std::array::from_fn::<f64, N, _>(|k| a[k] - b[k]))
}

/// Bounds of a cloud of points, as the validators measure a scene's size, with
/// the JSON path of the point farthest from the origin (named when it is too far).
#[derive(Clone, Debug)]
pub struct Extent<const N: usize> {
    pub min: [f64; N],
    pub max: [f64; N],
    pub farthest: String,
}

impl<const N: usize> Extent<N> {
    pub fn new() -> Self {
        Extent {
            min: [f64::INFINITY; N],
            max: [f64::NEG_INFINITY; N],
            farthest: String::new(),
        }
    }
    /// Grow by `p` (ignored unless finite: its own check reports it).
    pub fn grow(&mut self, p: [f64; N]) {
        self.grow_named("", p);
    }
    /// Grow by `p`, the point at JSON path `path`.
    pub fn grow_named(&mut self, path: &str, p: [f64; N]) {
        if p.iter().all(|v| v.is_finite()) {
            if p.iter().fold(0.0f64, |m, v| m.max(v.abs())) > self.reach() || self.farthest.is_empty() {
                self.farthest = path.to_string();
            }
            for (k, &x) in p.iter().enumerate() {
                self.min[k] = self.min[k].min(x);
                self.max[k] = self.max[k].max(x);
            }
        }
    }
    /// The diagonal (0 when empty).
    pub fn size(&self) -> f64 {
        if self.min[0] > self.max[0] {
            return 0.0;
        }
        distance(self.min, self.max)
    }
    /// The largest |coordinate| (0 when empty).
    pub fn reach(&self) -> f64 {
        if self.min[0] > self.max[0] {
            return 0.0;
        }
        (0..N).fold(0.0f64, |m, k| m.max(self.min[k].abs()).max(self.max[k].abs()))
    }
}

impl<const N: usize> Default for Extent<N> {
    fn default() -> Self {
        Self::new()
    }
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

    /// `v` finite and within `[lo, hi]`.
    pub fn within(&mut self, path: &str, v: f64, (lo, hi): (f64, f64)) -> bool {
        if !self.finite(path, v) {
            return false;
        }
        if !(lo..=hi).contains(&v) {
            self.fail(path, format!("must lie between {lo:e} and {hi:e}, got {v:e}"));
            return false;
        }
        true
    }

    /// Every coordinate finite and within ±[`MAX_COORD`] (each bad one reported
    /// with its index).
    pub fn point<const N: usize>(&mut self, path: &str, p: [f64; N]) -> bool {
        (0..N).fold(true, |ok, k| {
            let path = format!("{path}[{k}]");
            let good = self.finite(&path, p[k]) && {
                let inside = p[k].abs() <= MAX_COORD;
                if !inside {
                    self.fail(path, format!("must lie within ±{MAX_COORD:e}, got {:e}", p[k]));
                }
                inside
            };
            good & ok
        })
    }

    /// A direction: finite, of length within [`limits::DIRECTION_LENGTH`] (it is
    /// normalised).
    pub fn direction<const N: usize>(&mut self, path: &str, d: [f64; N]) -> bool {
        if !(0..N).fold(true, |ok, k| self.finite(&format!("{path}[{k}]"), d[k]) & ok) {
            return false;
        }
        let (lo, hi) = limits::DIRECTION_LENGTH;
        let len = length(d);
        if len == 0.0 {
            self.fail(path, "must not be the zero vector");
            return false;
        }
        if !(lo..=hi).contains(&len) {
            self.fail(
                path,
                format!("a direction must have a length between {lo:e} and {hi:e}, got {len:e}"),
            );
            return false;
        }
        true
    }

    /// `a` and `b` at least [`limits::MIN_SEPARATION`]·`size` apart.
    pub fn apart<const N: usize>(&mut self, path: &str, a: [f64; N], b: [f64; N], size: f64, what: &str) -> bool {
        let min = limits::MIN_SEPARATION * size;
        let d = distance(a, b);
        if d < min || d == 0.0 {
            self.fail(
                path,
                format!(
                    "{what}: {d:e} apart, less than {:e} of the scene size ({min:e})",
                    limits::MIN_SEPARATION
                ),
            );
            return false;
        }
        true
    }

    /// The scene's size (from `extent`; a size problem is reported at `path`) and
    /// where it lies (a problem reported at the farthest point's path).
    pub fn scene_size<const N: usize>(&mut self, path: &str, extent: &Extent<N>) -> bool {
        let (size, reach) = (extent.size(), extent.reach());
        if size < limits::MIN_SCENE_SIZE {
            self.fail(
                path,
                format!(
                    "the scene is {size:e} across; it must be at least {:e}",
                    limits::MIN_SCENE_SIZE
                ),
            );
            return false;
        }
        if reach > limits::MAX_SIZES_FROM_ORIGIN * size {
            let at = if extent.farthest.is_empty() {
                path
            } else {
                &extent.farthest
            };
            self.fail(
                at,
                format!(
                    "the scene ({size:e} across) lies {reach:e} from the origin, more than {:e} of its sizes: \
                     move it towards the origin so that f64 resolves its details",
                    limits::MAX_SIZES_FROM_ORIGIN
                ),
            );
            return false;
        }
        true
    }

    /// A colour's channels: finite, each 0 or within `range`.
    fn channels(&mut self, path: &str, c: &Color, range: (f64, f64), what: &str) {
        for (i, &v) in c.0.iter().enumerate() {
            let p = format!("{path}[{i}]");
            if !self.finite(&p, v) {
                continue;
            }
            let (lo, hi) = range;
            if v < 0.0 {
                self.fail(p, format!("must not be negative, got {v}"));
            } else if v > hi {
                self.fail(p, format!("must be at most {}, got {}", shown(hi), shown(v)));
            } else if !zero_or_within(v, range) {
                self.fail(
                    p,
                    format!("{what} must be 0 or at least {}, got {}", shown(lo), shown(v)),
                );
            }
        }
    }

    /// Radiance, intensity or irradiance: 0 or within [`limits::RADIANCE`].
    pub fn radiometric(&mut self, path: &str, c: &Color) {
        self.channels(path, c, limits::RADIANCE, "a radiometric value");
    }

    /// A diffuse reflectance: 0 or within [10⁻²⁰, 1].
    pub fn reflectance(&mut self, path: &str, c: &Color) {
        self.channels(path, c, (limits::RADIANCE.0, 1.0), "a reflectance");
    }

    /// σ_a or σ_s: 0 or within [`limits::SIGMA`].
    pub fn coefficient(&mut self, path: &str, c: &Color) {
        self.channels(path, c, limits::SIGMA, "a coefficient");
    }

    /// An axis-aligned box `{path}.min`–`{path}.max`, each side at least
    /// [`limits::MIN_SEPARATION`]·`size` (pass 0 before the size is known).
    pub fn bounds<const N: usize>(&mut self, path: &str, min: [f64; N], max: [f64; N], size: f64) -> bool {
        let ok = self.point(&format!("{path}.min"), min) & self.point(&format!("{path}.max"), max);
        if ok && !(0..N).all(|k| min[k] < max[k]) {
            self.fail(format!("{path}.max"), "must be greater than min in every coordinate");
            return false;
        }
        let side = (0..N).fold(f64::INFINITY, |m, k| m.min(max[k] - min[k]));
        if ok && side < limits::MIN_SEPARATION * size {
            self.fail(
                format!("{path}.max"),
                format!(
                    "a side of {side:e} is less than {:e} of the scene size ({size:e})",
                    limits::MIN_SEPARATION
                ),
            );
            return false;
        }
        ok
    }

    /// Henyey–Greenstein g within ±[`limits::MAX_ABS_G`].
    pub fn hg_g(&mut self, path: &str, g: f64) {
        let m = limits::MAX_ABS_G;
        if self.finite(path, g) && g.abs() > m {
            self.fail(path, format!("must lie between -{m} and {m}, got {g}"));
        }
    }

    /// The common fields of a `render` block.
    pub fn render_block(&mut self, resolution: [u32; 2], spp: u32, max_depth: u32, exposure: f64) {
        if let Some(why) = limits::resolution_problem(resolution[0], resolution[1]) {
            self.fail("render.resolution", why);
        }
        for (path, v, max) in [
            ("render.spp", spp, limits::MAX_SPP),
            ("render.max_depth", max_depth, limits::MAX_DEPTH),
        ] {
            if v == 0 {
                self.fail(path, "must be at least 1");
            } else if v > max {
                self.fail(path, format!("must be at most {max}, got {v}"));
            }
        }
        let e = limits::MAX_EXPOSURE;
        self.within("render.exposure", exposure, (-e, e));
    }
}
