//! "Copy as command": the `volcache` command lines that reproduce what the app shows,
//! headless. The field's final level is `volcache field` with the same parameters
//! (bit-identical: same seed, same per-pixel streams); the probe's aware and
//! unaware columns are `volcache probe --method aware|unaware` with the same seed.

use crate::flatland::field::FieldParams;
use crate::flatland::scene_desc::{Part, Quantity};
use glam::DVec2;

use super::compute::MethodParams;

/// Quote an argument for a POSIX shell when it needs it.
pub fn shell_quote(s: &str) -> String {
    let plain = !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "_-./,:=+@%".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

fn scene_arg(scene: Option<&str>) -> String {
    scene.map_or(String::new(), |s| format!(" {}", shell_quote(s)))
}

pub fn quantity_arg(q: Quantity) -> &'static str {
    match q {
        Quantity::Ls => "ls",
        Quantity::Fluence => "fluence",
    }
}

pub fn part_arg(p: Part) -> &'static str {
    match p {
        Part::All => "all",
        Part::Direct => "direct",
        Part::Single => "single",
        Part::Multiple => "multiple",
    }
}

/// `volcache field` for `p` (`scene`: None for the embedded default scene).
pub fn field_command(scene: Option<&str>, p: &FieldParams, exposure: f64, false_color: bool, out: &str) -> String {
    format!(
        "volcache field{} --res {}x{} --spp {} --seed {} --quantity {} --part {} --omega-o {} --exposure {}{} --out {}",
        scene_arg(scene),
        p.width,
        p.height,
        p.spp,
        p.seed,
        quantity_arg(p.quantity),
        part_arg(p.part),
        p.omega_o_deg,
        exposure,
        if false_color { " --false-color" } else { "" },
        shell_quote(out)
    )
}

/// `volcache probe` at `x` with `method` ("aware", "unaware" or "reference").
pub fn probe_command(
    scene: Option<&str>,
    x: DVec2,
    method: &str,
    m: &MethodParams,
    seed: u64,
    omega_o_deg: f64,
) -> String {
    let specific = if method == "reference" {
        format!("--spp {} --fd-step {}", m.ref_spp, m.fd_step)
    } else {
        format!("--rays {} --steps {} --paths {}", m.rays, m.steps, m.paths)
    };
    format!(
        "volcache probe{} --at {},{} --method {method} {specific} --seed {seed} --omega-o {omega_o_deg} --json",
        scene_arg(scene),
        x.x,
        x.y
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flatland::scene::Scene;

    #[test]
    fn commands_carry_every_parameter() {
        let mut p = FieldParams::from_scene(&Scene::default_scene());
        p.part = Part::Multiple;
        p.omega_o_deg = -30.0;
        assert_eq!(
            field_command(Some("my scenes/a.json"), &p, -1.5, true, "out/a.png"),
            "volcache field 'my scenes/a.json' --res 256x256 --spp 128 --seed 1 --quantity ls --part multiple \
             --omega-o -30 --exposure -1.5 --false-color --out out/a.png"
        );
        assert_eq!(
            field_command(None, &p, 0.0, false, "o.png"),
            "volcache field --res 256x256 --spp 128 --seed 1 --quantity ls --part multiple --omega-o -30 \
             --exposure 0 --out o.png"
        );
        let m = MethodParams::default();
        assert_eq!(
            probe_command(None, DVec2::new(-0.25, 0.5), "aware", &m, 1, 0.0),
            "volcache probe --at -0.25,0.5 --method aware --rays 2048 --steps 24 --paths 1 --seed 1 --omega-o 0 --json"
        );
        assert!(probe_command(None, DVec2::ZERO, "reference", &m, 1, 0.0).contains("--spp 20000 --fd-step 0.01"));
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
    }
}
