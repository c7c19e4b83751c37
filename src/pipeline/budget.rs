//! One budget parameter for a radiance cache: a budget B (1 = the reference point
//! below, 4 = four times its cost) decides the error threshold ε, the rays of each
//! record and, in 3D, the camera samples per pixel, so that a user who wants a
//! better image asks for more budget and the schedule spends it where the error
//! model says it pays. Beside the model, a budget samples the straight light per
//! point (2D: [`flatland_direct_share`]; 3D: [`VOLUME_DIRECT_SAMPLES`]), in 2D
//! limits records' reach past edges ([`flatland_edge_reach`]) and in 3D places
//! records over one camera sample in eight ([`VOLUME_PLACED_SHARE`]).
//!
//! The error model: the squared error is a sum of terms, each a power of one knob,
//! - the interpolation error ∝ ε^p, its square A ε^{2p}, with records K ∝ ε^−q;
//! - the records' noise, C / rays (Monte Carlo);
//! - in 3D, the camera samples' noise, D / spp (the pixel's footprint, the first
//!   surface's light and the march are sampled per camera sample), whose cost
//!   grows as spp^s (s measured while the placement visited every camera
//!   sample's march points and placed more records for them; since a budget
//!   places over one in eight, the image's own cost, linear in spp, is most of
//!   it, and s has not been re-fitted).
//!
//! The placement's time is ∝ K · rays. Minimising the sum at a cost T ∝
//! ε^−q · rays · spp^s, Lagrange's condition makes every term fall alike, as
//! T^−γ with γ = 1 / (1 + q/(2p) + s): ε ∝ T^{−γ/(2p)}, rays ∝ T^γ, spp ∝ T^γ, and
//! the error ∝ T^{−γ/2}. (2D fields have no camera samples: s = 0, γ = 2p/(2p+q).)
//! In 3D, B = 1 is a point where the measurements saw the terms alike, so that
//! the schedule starts balanced and stays so. In 2D the terms are alike at a
//! larger budget (≈ 4.7, [`ErrorModel::balanced_eps_scale`]): from B = 1 up to it
//! the budget goes to ε alone.

/// A measured error model: exponents and the budget's reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorModel {
    /// Exponent of the interpolation error in ε.
    pub error_exponent_p: f64,
    /// Exponent of the record count in 1/ε.
    pub count_exponent_q: f64,
    /// Exponent of the cost in the camera samples per pixel, and the camera
    /// samples at budget 1 (None: the method has no camera samples to schedule).
    pub camera: Option<(f64, f64)>,
    /// Rays per record at budget 1.
    pub rays_at_one: f64,
    /// Where the terms were measured alike when that is not at budget 1: ε there
    /// as a multiple of budget 1's, with budget 1's rays. From budget 1 to that
    /// budget (ε^−q of budget 1's cost) the rays stay at budget 1's — fewer
    /// directions miss thin features, an error more records do not remove — and ε
    /// takes the whole budget (ε ∝ B^−1/q); above it, and below budget 1, the
    /// schedule of equal terms. None: budget 1 is balanced, equal terms throughout.
    pub balanced_eps_scale: Option<f64>,
}

/// 2D fields (`volcache caches --budget`), measured with the budget's straight
/// light per pixel and edge reach: `volcache caches --eps --rays --edge-reach
/// max(1, 4 (ε/0.025)^0.55)`, ε 0.05 … 0.00015 × 64 … 2048 rays, on
/// `occluder.json` at 128² (256 straight-light samples per pixel) and
/// `windows.json` at 220×145 (32,768-spp references, seed 1; numbers in the
/// commit). The fit E² = A ε^{2p} + C/rays (≥ 256 rays, the reference's noise
/// taken out) gave p = 0.335 / 0.339, K ∝ ε^−0.45 / ε^−0.51, and the terms
/// alike with 256 rays at ε 0.0004 (occluder) and 0.0069 (windows); below 256
/// rays the error rose faster than 1/rays (occluder at ε 0.0015: 0.0060 / 0.014
/// / 0.016 at 256 / 128 / 64). Balanced at ε 0.001 (budget ≈ 4.7), the model
/// puts both scenes within 1.25× of their own best time at every budget (a
/// balance at budget 1's ε 0.025, the schedule until this commit, lost 5.5× on
/// the occluder; at 0.0004, 1.7× on windows). ε ∝ B^−2.1 up to it, then
/// ε ∝ B^−0.88 and rays ∝ B^0.58; the error ∝ B^−0.29 there.
pub const FLATLAND: ErrorModel = ErrorModel {
    error_exponent_p: 0.33,
    count_exponent_q: 0.48,
    camera: None,
    rays_at_one: 256.0,
    balanced_eps_scale: Some(0.04),
};

/// ε of a 2D field at budget 1.
pub const EPS_AT_ONE: f64 = 0.025;

/// The light arriving straight from lights with an extent (emitting segments) in
/// a 2D field under a budget: sampled at every pixel (`CacheSettings::
/// direct_samples`; the records then hold only scattered and reflected light),
/// at least this many samples, raised to a share of the placement's rays
/// ([`flatland_direct_share`]). Delta lights need none: their straight light is
/// per pixel at every budget.
///
/// Why per pixel: the straight light of an emitter seen past an occluder's end
/// has a shadow edge no record's Taylor expansion follows, and records that hold
/// it are placed for it. `occluder.json` at 128² (16,384-spp reference, seed 1),
/// budgets ¼ / 1 / 4 / 16: cached 0.047 / 0.037 / 0.036 / 0.025, with 16 samples
/// per pixel 0.019 / 0.017 / 0.012 / 0.0075 in about the same time (fewer
/// records: 38 → 32 at budget 1, 123 → 89 at 16); `forest.json` at 160×120:
/// 3.6 / 2.9 / 2.5 / 1.8 · 10⁻³ → 2.0 / 1.6 / 1.2 / 0.97 · 10⁻³ with 64 samples.
pub const FLATLAND_DIRECT_MIN_SAMPLES: u32 = 4;

/// The share of a 2D placement's rays per pixel spent on the straight light's
/// samples at budget 1, and its exponent in the budget.
///
/// How many samples: they are one stratified set, whose squared error fell as
/// n^−1.8 … n^−2 (occluder at budget 16: 8.6·10⁻⁵, 5.4·10⁻⁶, 2.2·10⁻⁷ at 4, 16,
/// 64 samples; forest at budget 1: 1.8, 0.54, 0.15, 0.03 · 10⁻⁶ at 16 … 128).
/// Equal marginal gains (the records' squared error ∝ T_p^−γ, γ = 2p/(2p+q) of
/// [`FLATLAND`]; the samples' cost ∝ n) put n³ ∝ (D/E_p)·(T_p/c): n grows with the
/// records' cost per pixel, and with the budget as T_p^{(1+γ)/3} ≈ B^0.5 — a
/// share of the placement's rays falling as B^−0.5. At budget 1 the optimum was
/// 10–14 samples on the occluder (110 placement rays per pixel) and 80–100 on
/// the forest (876): a quarter of the placement's rays (14 and 110 samples).
pub const FLATLAND_DIRECT_SHARE_AT_ONE: f64 = 0.25;
/// The exponent of the straight light's share of the rays in a 2D budget.
pub const FLATLAND_DIRECT_SHARE_EXPONENT: f64 = -0.5;

/// The straight light's share of the placement's rays in a 2D field at budget `b`.
pub fn flatland_direct_share(b: f64) -> f64 {
    let b = b.clamp(MIN_BUDGET, MAX_BUDGET);
    FLATLAND_DIRECT_SHARE_AT_ONE * b.powf(FLATLAND_DIRECT_SHARE_EXPONENT)
}

/// The points (pixels in the medium) at which [`FLATLAND_DIRECT_SHARE_AT_ONE`] was
/// measured: the occluder at 128² (the forest's 160×120 is within 1.11× of it in
/// [`shared_direct_samples`]' scaling).
pub const FLATLAND_DIRECT_SHARE_POINTS: f64 = 16384.0;

/// Samples per point of the straight light: `share` of the placement's `rays` per
/// point served (two rays a sample) at [`FLATLAND_DIRECT_SHARE_POINTS`] points,
/// scaled by (points / those points)^{2/3}; at least `min`, at most 2^16.
///
/// Why the scaling: the marginal-gain rule of [`FLATLAND_DIRECT_SHARE_AT_ONE`]
/// puts n³ ∝ T_p / (E_p² P) for P points, so at a given placement cost n falls
/// as P^{−1/3}, not as the share's P^{−1}: the records' error does not grow with
/// the pixels, the straight light's noise per pixel does not fall with them.
/// Measured (true RMSE, the reference's noise taken out): `forest.json` at
/// 640×480 budget 4, the plain share's 22 samples 1.42·10⁻³ in 21.9 s, 88
/// samples 8.4·10⁻⁴ in 28 s, this rule's 153 7.6·10⁻⁴ in 39 s; `occluder.json` at
/// 256², budgets 1 / 4 / 16, plain share 4 / 5 / 11 samples 0.0197 / 0.0233 /
/// 0.0120, 8 / 16 / 32
/// samples 0.0181 / 0.0213 / 0.0110 at ≤ 1.35× the time; `forest.json` at 40×30,
/// budgets 1 / 4, plain share 1132 / 1291 samples 1.67 / 0.568·10⁻³ in 2.6 / 5.4
/// s, 200 samples (this rule: ≈ 200) 1.67 / 0.589·10⁻³ in 2.1 / 4.7 s.
pub fn shared_direct_samples(min: u32, share: f64, rays: u64, points: usize) -> u32 {
    let points = points.max(1) as f64;
    let per_point = rays as f64 / points;
    let scale = (points / FLATLAND_DIRECT_SHARE_POINTS).powf(2.0 / 3.0);
    let n = (share * per_point / 2.0 * scale).round();
    if n.is_finite() {
        (n as u32).min(1 << 16).max(min)
    } else {
        min
    }
}

/// The edge reach of a 2D budget (`CacheSettings::edge_reach`): a record's radii
/// at most `k` × its distance to the nearest surface edge or point light it sees,
/// k = max(1, 4 √(ε/ε₁)) with ε₁ budget 1's ε. Why: around an edge the light turns
/// with the angle seen from it, so a first-order expansion at distance d from an
/// edge whose light jumps by ΔL errs by ≈ ΔL (r/d)² at radius r; keeping that
/// below ε L asks r ≤ d √(εL/ΔL): a reach ∝ √ε. Where the reach binds, records
/// crowd the edges at a count ε does not set (130 on the occluder at k = 0.5,
/// 2,400 on the forest at k = 1, budget 1), so it is not taken below 1. Measured
/// on `occluder.json` at 128² (32,768-spp reference, seed 1), without → with a
/// reach of 1: ε 0.0020 / 0.00057 / 0.00031 / 0.00016 (1162 … 5270 rays) RMSE
/// 0.0072 / 0.0044 / 0.0093 / 0.0061 → 0.0062 / 0.0040 / 0.0042 / 0.0032 (the
/// error no longer rises as ε falls: records beside the emitter's ends reached
/// across them) in 1.0–1.04× the time; at budget 1 a reach of 1 cost (0.0172 →
/// 0.0223), of 2 a little (0.0188).
pub fn flatland_edge_reach(b: f64) -> f64 {
    (4.0 * FLATLAND.schedule(b).eps_scale.sqrt()).max(1.0)
}

/// Phase-sampled directions per pixel of a 2D field's once-scattered point-light
/// light (`CacheSettings::point_scatter`) at budget one, and their growth: ∝ b,
/// so that the part keeps its share of the time and its variance falls as 1/b,
/// as path tracing's. Measured on `shaded_lamp.json` at 128² (4,096-spp
/// reference, noise ≈ 0.09, seed 1): at budget 1, 0 / 4 / 16 / 64 / 256 / 1024
/// directions gave RMSE 1.03 / 1.00 / 0.58 / 0.43 / 0.41 / 0.40 in 2.3 / 2.1 /
/// 2.1 / 2.5 / 3.1 / 6.2 s (443 records, the cache's bias +0.10 → +0.017); at
/// budget 4, 0 / 64 / 256 gave 0.95 / 0.37 / 0.35 in 3.8 / 4.1 / 4.8 s.
pub const FLATLAND_POINT_SCATTER_AT_ONE: f64 = 64.0;
/// Bounds of [`flatland_point_scatter`]: below 16 the part's noise dominates;
/// above 4,096 a pixel costs more than a record.
const FLATLAND_POINT_SCATTER_RANGE: (f64, f64) = (16.0, 4096.0);

/// Directions per pixel of a 2D field's once-scattered point-light light at
/// budget `b`.
pub fn flatland_point_scatter(b: f64) -> u32 {
    let b = b.clamp(MIN_BUDGET, MAX_BUDGET);
    let (lo, hi) = FLATLAND_POINT_SCATTER_RANGE;
    (FLATLAND_POINT_SCATTER_AT_ONE * b).clamp(lo, hi).round() as u32
}

/// Paths per pixel of a 2D field's pixels near a point light
/// (`CacheSettings::near_light_paths`) at budget one, and their growth: ∝ √b.
/// Those pixels are few (3% of `shaded_lamp.json`'s) and a path there is cheap
/// against a record, so they take many; √b rather than b because the records'
/// error falls slower than 1/√time, and the near pixels' should keep pace with
/// it, not outrun it. Measured on `shaded_lamp.json` at 128² (4,096-spp
/// reference, noise ≈ 0.09, seed 1, one thread): budget ¼ without / 64 / 256
/// paths RMSE 0.71 / 0.57 / 0.45 in 1.6 / 1.7 / 2.1 s; budget 1 without / 256 /
/// 1,024: 0.44 / 0.30 / 0.25 in 4.0 / 4.4 / 5.8 s; budget 4 without / 1,024 /
/// 4,096: 0.35 / 0.25 / 0.23 in 8.5 / 10.4 / 15.9 s.
pub const FLATLAND_NEAR_LIGHT_PATHS_AT_ONE: f64 = 1024.0;
/// Bounds of [`flatland_near_light_paths`].
const FLATLAND_NEAR_LIGHT_PATHS_RANGE: (f64, f64) = (256.0, 16384.0);

/// Paths per pixel near a point light in a 2D field at budget `b`.
pub fn flatland_near_light_paths(b: f64) -> u32 {
    let b = b.clamp(MIN_BUDGET, MAX_BUDGET);
    let (lo, hi) = FLATLAND_NEAR_LIGHT_PATHS_RANGE;
    (FLATLAND_NEAR_LIGHT_PATHS_AT_ONE * b.sqrt()).clamp(lo, hi).round() as u32
}

/// 3D images (`volcache render3d --budget`). First measured at 24×18 with the
/// straight light cached (ε 1, ¼, 1/16 of the scene's default × 64 / 256 / 1024
/// rays × 4 / 16 / 64 camera samples): p ≈ 0.5, K ∝ ε^−0.5, terms alike at a
/// quarter of the default ε, 256 rays and 16 camera samples. Re-measured since
/// the budget samples the straight light per march point, on `fog_box.json` and
/// `lamp_fog.json` at 48×36 (seeds 1–2, two 65,536-spp references per scene
/// whose own noise, 0.0012 / 0.0031 in the medium part, is taken out), ε 4, 1, ¼
/// × that quarter × 96 / 256 rays × 16 / 64 / 256 camera samples: at 16 camera
/// samples the camera samples held the error (fog_box medium RMSE 0.0035 at 16,
/// 0.0023 at 64, 0.0019 at 256, whatever ε; lamp_fog 0.024 / 0.019 at 16 / 64),
/// and they cost less than the model counted: the time ∝ spp^0.39 from 16 to 64
/// (K ∝ ε^−0.56 / ε^−0.46 and ∝ spp^0.09; the image's own time is linear in spp,
/// its share 14% at 16, 32% at 64). Fitting E² = A ε^{2p} + C/rays + D/spp and
/// the time (a K (rays + r₀) + b spp) per scene and taking each scene's best
/// mix at every budget ¼ … 64 and at 1, 4 and 16 × the pixels, this schedule —
/// 64 camera samples at budget 1, the cost exponent 0.4 — takes at most 2.2× the
/// best time on either (the budget-1 point of 16 camera samples: 6.4×; the
/// fitted optima differ: fog_box gains nothing from ε in that range, lamp_fog
/// most). ε ∝ B^−0.53, rays and spp ∝ B^0.53, error ∝ B^−0.26. Where the
/// image's camera samples cost more than in these scenes the exponent is too
/// low: on the staircase at 160×120 (72–74% of the time in the image) the image
/// came out ≈ 10% lower at equal time than with 16 camera samples but the
/// medium part higher (README).
pub const VOLUME: ErrorModel = ErrorModel {
    error_exponent_p: 0.5,
    count_exponent_q: 0.5,
    camera: Some((0.4, 64.0)),
    rays_at_one: 256.0,
    balanced_eps_scale: None,
};

/// A 3D record's radii at most this multiple of its distance to the nearest
/// point light (`CacheSettings::lamp_reach`, on by default in 3D at every
/// budget): a Taylor expansion of the 1/ρ peak of the light scattered around a
/// lamp converges only within ρ. Why 2 and not 1 is measured, its reason a
/// guess: near the lamp each record's value is heavy-tailed noise, and a smaller
/// reach leaves fewer records overlapping there to average it.
/// Measured at budget 1, 32×24 (RMSE against 16,384–32,768-spp path traced
/// references, relative standard error 2.2–2.4%), without → k = 1 / 1.5 / 2 / 3:
/// `deep_lamp.json` seeds 1–6, mean 0.29 (seed 3: 1.06) → 0.107 / 0.099 / 0.095
/// / 0.102 (k = 4: 0.111, seed 3 0.146); a lamp 4.4 mean free paths before the
/// camera (σ_s 3.8, g −0.4, seeds 1–4) mean 0.250 → 0.300 / 0.256 / 0.249 /
/// 0.250; a lamp seen from 6.5 mean free paths and `mesh_in_fog.json` (seeds 1–3) unchanged within
/// 0.5% at k = 2 (at k = 1 within 0.6%, but for mesh_in_fog's seed 3, −7%).
/// Rays within ±1% of without at k ≥ 1 (k = ½: +18%). Those seeds are the
/// camera's (`--seed`); the records' light fields shared cache seed 1, so the
/// seeds vary where records fall, not the light fields' streams.
pub const VOLUME_LAMP_REACH: f64 = 2.0;

/// ε of a 3D image at budget 1, as a multiple of the scene's default
/// (`volume::cached::default_eps`).
pub const VOLUME_EPS_AT_ONE: f64 = 0.25;

/// Samples per march point of the light arriving straight from the lights, at
/// every budget of a 3D image (`CacheSettings::direct_samples`): the records then
/// hold only scattered and reflected light. Why: with the straight light cached, a
/// small lamp is missed by few directions (lamp_fog at budget 1/4: 115 directions,
/// medium RMSE 0.16 at 24×18) and its sharp near field shapes every record.
/// Measured at 24×18 (seeds 1–2, budgets 1/4, 1, 4; 65,536-spp references) and at
/// 96×72 (16,384 spp): medium RMSE fog_box 0.0098 / 0.0074 → 0.0059 / 0.0050 at
/// budget 1 (24×18), 0.0078 → 0.0039 (96×72); lamp_fog 0.16 → 0.036 / 0.032 at 1/4,
/// 0.065 / 0.046 → 0.034 / 0.023 at 1 (24×18), 0.045 → 0.015 (96×72), in 0.85–1.15×
/// the time (fewer records: the field left is smoother). One sample per point gave
/// most of lamp_fog's gain but fog_box's error fell 1.5× more with 4 (at 1.2× the
/// time at 96×72). The image's share of the time grows with these samples (96×72:
/// 10% → 32%), which the camera's cost exponent does not count.
pub const VOLUME_DIRECT_SAMPLES: u32 = 4;

/// A 3D budget's placement visits one camera sample of a pixel in this many
/// (at least one): the others read the records, and a march point no record
/// covers is path traced (counted as uncovered). Why: the records' count and cost
/// barely follow the camera samples (K ∝ spp^0.09) but the placement's walk over
/// their march points is linear in them, and the image's error at budget 1 is
/// the camera samples' noise, not the records'. Measured at budget 1 placing
/// over 8 / 16 / 32 / 64 of the 64 camera samples (seeds 1–2; 48×36 against
/// 65,536-spp references, the staircase at 80×60 against 16,384 spp), 8 against
/// all 64 moved the medium RMSE by −2 … +4% (fog_box +0.5 / +2.3%, lamp_fog
/// −1.8 / +1.4%, the budget test's panel scene −1.0 / +4.3%, the staircase
/// +3.5 / +1.4%; seed-to-seed spread 3–7%) in 0.70–0.82× the time (fog_box 11.8
/// → 9.1 s, the staircase 59 → 48 s) with 76–88% of the records; 2 and 4 placed
/// samples cost more error (lamp_fog +7% / +2%, the staircase +10% at 2) for
/// little time saved. Jarosz 2008's equal-count search probes one placement per
/// ε, so it gains the same factor per probe.
pub const VOLUME_PLACED_SHARE: u32 = 8;

/// The camera samples a 3D budget's placement visits of `spp` per pixel.
pub fn volume_placed_spp(spp: u32) -> u32 {
    spp.div_ceil(VOLUME_PLACED_SHARE).max(1)
}

/// The smallest budget (2D: ε ≈ 0.28, 51 rays per record: below, records are noise).
pub const MIN_BUDGET: f64 = 1.0 / 16.0;
/// The largest budget (2D: ε ≈ 2.6·10^−6, ≈ 13,000 rays per record).
pub const MAX_BUDGET: f64 = 4096.0;

/// What a budget sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// ε as a multiple of ε at budget 1.
    pub eps_scale: f64,
    pub rays: usize,
    /// Camera samples per pixel (None where the model has none).
    pub spp: Option<u32>,
}

impl ErrorModel {
    /// The exponents of ε, rays and camera samples in the budget.
    fn exponents(&self) -> (f64, f64) {
        let (p, q) = (self.error_exponent_p, self.count_exponent_q);
        let s = self.camera.map_or(0.0, |(s, _)| s);
        // γ / (2p) = 1 / (2p + q + 2p s); with s = 0 the same operations as
        // 1 / (2p + q).
        let denom = 2.0 * p + q + 2.0 * p * s;
        (-1.0 / denom, 2.0 * p / denom)
    }

    /// The schedule of budget `b` (in [`MIN_BUDGET`], [`MAX_BUDGET`]; callers check).
    pub fn schedule(&self, b: f64) -> Schedule {
        let b = b.clamp(MIN_BUDGET, MAX_BUDGET);
        let (eps_exp, gamma) = self.exponents();
        // Equal terms from (budget `from`, ε scale `eps_at`) on.
        let equal_terms = |from: f64, eps_at: f64| {
            let grow = (b / from).powf(gamma);
            Schedule {
                eps_scale: eps_at * (b / from).powf(eps_exp),
                rays: (self.rays_at_one * grow).round() as usize,
                spp: self.camera.map(|(_, spp)| (spp * grow).round().max(1.0) as u32),
            }
        };
        match self.balanced_eps_scale {
            Some(eps_at) if b > 1.0 => {
                let balanced = eps_at.powf(-self.count_exponent_q);
                if b >= balanced {
                    equal_terms(balanced, eps_at)
                } else {
                    Schedule {
                        eps_scale: b.powf(-1.0 / self.count_exponent_q),
                        rays: self.rays_at_one.round() as usize,
                        spp: self.camera.map(|(_, spp)| spp.round().max(1.0) as u32),
                    }
                }
            }
            // Below budget 1 records are few, their count held up by covering the
            // field, so a larger ε buys little time back: fewer rays do.
            _ => equal_terms(1.0, 1.0),
        }
    }
}

/// The 2D schedule of budget `b`: ε and rays per record.
pub fn schedule(b: f64) -> (f64, usize) {
    let s = FLATLAND.schedule(b);
    (EPS_AT_ONE * s.eps_scale, s.rays)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model's cost ε^−q · rays · spp^s, relative to budget 1's.
    fn model_cost(m: &ErrorModel, s: &Schedule) -> f64 {
        let camera = match (m.camera, s.spp) {
            (Some((e, at_one)), Some(spp)) => (spp as f64 / at_one).powf(e),
            _ => 1.0,
        };
        s.eps_scale.powf(-m.count_exponent_q) * s.rays as f64 / m.rays_at_one * camera
    }

    #[test]
    fn the_pixels_near_a_lamp_take_paths_as_the_root_of_the_budget() {
        let paths: Vec<u32> = [0.25, 1.0, 4.0, 16.0].map(flatland_near_light_paths).to_vec();
        assert_eq!(paths, [512, 1024, 2048, 4096]);
        // Bounded both ways, also for budgets outside the schedule's range.
        assert_eq!(flatland_near_light_paths(0.0), 256);
        assert_eq!(flatland_near_light_paths(1e9), 16384);
    }

    #[test]
    fn budget_one_is_the_reference_point_and_cost_grows_with_the_budget() {
        assert_eq!(schedule(1.0), (EPS_AT_ONE, FLATLAND.rays_at_one as usize));
        let v = VOLUME.schedule(1.0);
        assert_eq!((v.eps_scale, v.rays), (1.0, VOLUME.rays_at_one as usize));
        assert_eq!(v.spp.map(f64::from), VOLUME.camera.map(|c| c.1));
        // The cost grows as the budget (rays and camera samples rounded).
        for m in [FLATLAND, VOLUME] {
            for b in [0.25, 4.0, 16.0, MAX_BUDGET] {
                let cost = model_cost(&m, &m.schedule(b));
                assert!((cost / b - 1.0).abs() < 0.05, "{m:?} budget {b}: model cost {cost}");
            }
        }
    }

    /// A 3D budget places over one camera sample in eight, at least one.
    #[test]
    fn a_3d_placement_visits_one_camera_sample_in_eight() {
        let placed: Vec<u32> = [1, 7, 8, 9, 31, 64, 133].map(volume_placed_spp).into();
        assert_eq!(placed, [1, 1, 1, 2, 4, 8, 17]);
        assert_eq!(volume_placed_spp(0), 1);
    }

    /// The straight light's share of a 2D placement's rays: a quarter at budget 1,
    /// falling as the budget's marginal-gain rule says (n ∝ T^{(1+γ)/3},
    /// γ = 2p/(2p+q): the share ∝ T^{(1+γ)/3 − 1}); the samples it gives.
    #[test]
    fn the_straight_light_share_falls_as_the_square_root_of_the_budget() {
        let (p, q) = (FLATLAND.error_exponent_p, FLATLAND.count_exponent_q);
        let gamma = 2.0 * p / (2.0 * p + q);
        assert!((FLATLAND_DIRECT_SHARE_EXPONENT - ((1.0 + gamma) / 3.0 - 1.0)).abs() < 0.05);
        assert_eq!(flatland_direct_share(1.0), 0.25);
        assert_eq!(flatland_direct_share(16.0), 0.0625);
        assert_eq!(flatland_direct_share(1e9), flatland_direct_share(MAX_BUDGET));
        // 110 rays per point at a quarter at the measured points: 14 samples; at 8×
        // the points and the same rays per point (8× the placement's rays) 8^(2/3)
        // = 4 times that, at ⅛ the points a quarter (3: the floor); the floor; no
        // points (one); huge.
        let at = FLATLAND_DIRECT_SHARE_POINTS as usize;
        assert_eq!(shared_direct_samples(4, 0.25, 110 * at as u64, at), 14);
        assert_eq!(shared_direct_samples(4, 0.25, 110 * 8 * at as u64, 8 * at), 55);
        assert_eq!(shared_direct_samples(4, 0.25, 110 * (at / 8) as u64, at / 8), 4);
        assert_eq!(shared_direct_samples(4, 0.25, 10 * at as u64, at), 4);
        assert_eq!(shared_direct_samples(4, 0.25, 1000 * at as u64, 0), 3175);
        assert_eq!(shared_direct_samples(4, 0.25, u64::MAX, 1), 1 << 16);
        assert_eq!(shared_direct_samples(4, f64::NAN, 1000, 1), 4);
    }

    #[test]
    fn the_edge_reach_tightens_with_the_budget_down_to_one() {
        assert_eq!(flatland_edge_reach(1.0), 4.0);
        assert!(flatland_edge_reach(MIN_BUDGET) > 8.0);
        assert!(flatland_edge_reach(0.5) > flatland_edge_reach(0.7));
        for b in [4.0, 16.0, 64.0, f64::INFINITY] {
            assert_eq!(flatland_edge_reach(b), 1.0);
        }
    }

    /// From budget 1 to the 2D model's balanced budget the rays stay and ε takes
    /// the budget; below 1 and from it on, the terms fall alike (ε^{2p} and 1/rays
    /// by one factor).
    #[test]
    fn the_2d_rays_stay_until_the_terms_are_balanced() {
        let eps_at = FLATLAND.balanced_eps_scale.expect("2D is balanced above budget 1");
        let balanced = eps_at.powf(-FLATLAND.count_exponent_q);
        let rays_at_one = FLATLAND.rays_at_one as usize;
        for b in [1.0, 2.0, 4.0, balanced] {
            assert_eq!(FLATLAND.schedule(b).rays, rays_at_one, "budget {b}");
        }
        assert!(FLATLAND.schedule(0.5).rays < rays_at_one);
        let at = FLATLAND.schedule(balanced);
        assert!((at.eps_scale - eps_at).abs() < 1e-12, "{at:?}");
        let (a, b) = (FLATLAND.schedule(2.0 * balanced), FLATLAND.schedule(128.0 * balanced));
        let interp = (b.eps_scale / a.eps_scale).powf(2.0 * FLATLAND.error_exponent_p);
        let rays = a.rays as f64 / b.rays as f64;
        assert!((interp / rays - 1.0).abs() < 0.01, "{interp} {rays}");
    }

    /// Every error term falls alike: ε^{2p}, 1/rays and 1/spp by one factor.
    #[test]
    fn the_terms_fall_alike() {
        let (a, b) = (VOLUME.schedule(1.0), VOLUME.schedule(64.0));
        let interp = (b.eps_scale / a.eps_scale).powf(2.0 * VOLUME.error_exponent_p);
        let rays = a.rays as f64 / b.rays as f64;
        let spp = a.spp.unwrap() as f64 / b.spp.unwrap() as f64;
        assert!(
            (interp / rays - 1.0).abs() < 0.01 && (spp / rays - 1.0).abs() < 0.05,
            "{interp} {rays} {spp}"
        );
    }

    #[test]
    fn the_schedule_is_monotone() {
        for m in [FLATLAND, VOLUME] {
            let mut last = m.schedule(MIN_BUDGET);
            for k in 1..=32 {
                let s = m.schedule(MIN_BUDGET * 2f64.powf(k as f64 * 0.5));
                assert!(
                    s.eps_scale < last.eps_scale && s.rays >= last.rays && s.spp >= last.spp,
                    "{s:?} after {last:?}"
                );
                last = s;
            }
        }
    }
}
