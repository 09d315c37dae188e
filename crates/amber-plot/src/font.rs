//! The one font every picture and chart writes its text in: the vendored DejaVu Sans,
//! registered as plotters' "sans-serif" so no system font is needed.

use std::sync::Once;

use plotters::style::FontStyle;

/// The font family every text style names.
pub(crate) const FONT_FAMILY: &str = "sans-serif";

/// Registers the vendored DejaVu Sans as [`FONT_FAMILY`] (once per process).
pub(crate) fn register_default_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, include_bytes!("../assets/DejaVuSans.ttf"))
            .unwrap_or_else(|_| unreachable!("the vendored DejaVuSans.ttf is a valid font"));
    });
}
