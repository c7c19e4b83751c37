//! Figures: drawing of data it is handed (tiny-skia); it never traces rays.
//!
//! - [`colormap`]: sRGB encoding, exposure tone mapping, viridis, a hue wheel.
//! - [`text`]: labels in DejaVu Sans (embedded).
//! - [`overlay`]: the scene (segments, lights, medium outline) over a panel, through
//!   a world → pixel [`View`].
//! - [`colorbar`]: false-colour scales, ticks and the colour bar.
//! - [`field_figure`](mod@field_figure): a radiance field as a finished figure.
//!
//! Files are written by [`crate::output`] (atomic PNG/EXR/JSON writers).

pub mod colorbar;
pub mod colormap;
pub mod field_figure;
pub mod overlay;
pub mod panel;
pub mod text;

pub use colorbar::{ColorScale, Tick, colorbar_width, draw_colorbar};
pub use colormap::{angle_color, srgb_encode, tonemap, viridis};
pub use field_figure::{
    FieldStyle, FigureOptions, INVALID_RGB, MappedField, NAN_RGB, field_color_scale, field_figure, field_figure_with,
    field_to_rgba, upscale_factor,
};
pub use overlay::{OverlayStyle, draw_scene};
pub use panel::{Canvas, View};
pub use text::{HAlign, VAlign, draw_text, draw_text_aligned, draw_text_vertical, text_metrics, text_width};
