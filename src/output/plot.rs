//! Shared plotting set-up for figures made with `plotters`.
//!
//! plotters' default font stack needs system fonts, which a fresh machine may lack; the crate is
//! built without it and draws text with `ab_glyph` from DejaVu Sans, embedded through the
//! `dejavu` crate. Call [`ensure_fonts`] before drawing any text.

use std::sync::Once;

use plotters::style::FontStyle;

/// The font family name to use in text styles.
pub const FONT: &str = "sans-serif";

/// Registers DejaVu Sans (regular, bold, oblique) under [`FONT`] once per process.
pub fn ensure_fonts() {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        for (style, bytes) in [
            (FontStyle::Normal, dejavu::sans::regular()),
            (FontStyle::Bold, dejavu::sans::bold()),
            (FontStyle::Oblique, dejavu::sans::oblique()),
            (FontStyle::Italic, dejavu::sans::oblique()),
        ] {
            // The bytes are a valid TTF shipped by the dejavu crate.
            plotters::style::register_font(FONT, style, bytes).unwrap_or_else(|_| panic!("DejaVu Sans loads"));
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::prelude::*;

    #[test]
    fn text_renders_with_the_embedded_font() {
        ensure_fonts();
        let (width, height) = (120u32, 40u32);
        let mut buffer = vec![255u8; (width * height * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
            root.draw_text("θ = 25 °C", &(FONT, 20).into_font().color(&BLACK), (5, 5))
                .unwrap();
            root.present().unwrap();
        }
        assert!(
            buffer.iter().any(|&b| b < 128),
            "some pixels are dark: the text was drawn"
        );
    }
}
