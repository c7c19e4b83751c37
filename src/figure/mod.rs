//! Figures: drawing of data it is handed (tiny-skia); it never traces rays.
//!
//! - [`colormap`]: sRGB encoding, exposure tone mapping, viridis, a hue wheel.
//! - [`text`]: labels in DejaVu Sans (embedded).
//! - [`overlay`]: the scene (segments, lights, medium outline) over a panel, through
//!   a world → pixel [`View`].
//! - [`colorbar`]: false-colour scales, ticks and the colour bar.
//! - [`field_figure`](mod@field_figure): a radiance field as a finished figure;
//!   [`exposure`]: its automatic exposure and the tone-mapped grey scale.
//! - [`gradient_color`](mod@gradient_color): gradients coloured by direction and log magnitude, and the
//!   colour wheel explaining it.
//! - [`gradient_figure`](mod@gradient_figure): the paper's gradient figure (panels per
//!   method) and the gradient's profile along a line.
//! - [`axis`], [`plot`]: line plots (linear or log axes, legends), alone or stacked.
//! - [`records`]: cache records drawn as their extents (the point-distribution
//!   insets), alone or over the scene and a dimmed field.
//! - [`error_map`]: per-pixel error against a reference in false colour.
//! - [`image3d`]: rendered 3D images: enlarged, zoomed insets, records projected
//!   into the image, error maps.
//! - [`compose`]: finished figures composed into captioned rows.
//!
//! Files are written by [`crate::output`] (atomic PNG/EXR/JSON writers).

pub mod axis;
pub mod colorbar;
pub mod colormap;
pub mod compose;
pub mod error_map;
pub mod exposure;
pub mod field_figure;
pub mod gradient_color;
pub mod gradient_figure;
pub mod image3d;
pub mod overlay;
pub mod panel;
pub mod plot;
mod plot_layout;
mod plot_series;
pub mod records;
#[cfg(test)]
mod synthetic;
pub mod text;

pub use colorbar::{ColorScale, Tick, colorbar_width, draw_colorbar};
pub use colormap::{angle_color, srgb_encode, tonemap, viridis};
pub use compose::{Cell, compose_grid};
pub use error_map::{error_field, error_map_figure, shared_error_range};
pub use exposure::{AUTO_EXPOSURE_PERCENTILE, auto_exposure, tonemap_grey, tonemap_scale};
pub use field_figure::{
    FieldStyle, FigureOptions, INVALID_RGB, MappedField, NAN_RGB, field_color_scale, field_figure, field_figure_with,
    field_to_rgba, upscale_factor,
};
pub use gradient_color::{
    GradientSample, colour_wheel_legend, gradient_brightness, gradient_color, grid_spacing, magnitude_range,
};
pub use gradient_figure::{
    AWARE_PURPLE, GradientProfile, GradientStyle, REFERENCE_BLUE, UNAWARE_ORANGE, gradient_figure, gradient_line_plot,
    gradient_panel,
};
pub use overlay::{OverlayStyle, draw_scene};
pub use panel::{Canvas, View};
pub use plot::{
    Axis, AxisMap, AxisTick, LineStyle, Plot, PlotLayout, Scale, Series, draw_plot, draw_plot_into, draw_plots_stacked,
};
pub use records::{RECORD_BLUE, RecordColor, RecordStyle, draw_records, record_color_scale, records_figure};
pub use text::{HAlign, VAlign, draw_text, draw_text_aligned, draw_text_vertical, text_metrics, text_width};
