//! `volcache figure`: the paper's figures, computed and drawn (PNG + JSON with every
//! number): the gradient figure, and the 2D and 3D comparisons at equal cache count.

use clap::Subcommand;
use std::process::ExitCode;

#[derive(Subcommand, Debug)]
pub enum FigureCommand {
    /// The paper's gradient figure: ∇L_s by ours (aware), Jarosz 2008 (unaware) and
    /// finite differences (reference) on a grid and along a line, per scattering part.
    Gradients(super::figure_gradients::GradientArgs),
    /// Reference, ours and Jarosz 2008 side by side at equal cache count: fields, cache
    /// distributions and error maps, with records, rays, time and RMSE in the captions.
    Compare(super::figure_compare::CompareArgs),
    /// 3D: reference, ours and Jarosz 2008 at equal cache count and path tracing at
    /// equal time, with zoomed insets, records projected into the image, error maps
    /// and the numbers.
    Compare3d(super::figure_compare3d::Compare3dArgs),
}

pub fn run(cmd: FigureCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        FigureCommand::Gradients(a) => super::figure_gradients::run(a),
        FigureCommand::Compare(a) => super::figure_compare::run(a),
        FigureCommand::Compare3d(a) => super::figure_compare3d::run(a),
    }
}
