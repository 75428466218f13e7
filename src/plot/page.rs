//! What the tools' HTML pages share (report's and stress's index.html): their style
//! sheet, inlined so that a page loads nothing, and HTML escaping.

/// The pages' style sheet (no url(), no @import: a page stands alone).
pub const STYLE: &str = include_str!("page.css");

/// `text` escaped for HTML text and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// An SVG document as an inline element (from `<svg` on: no XML prolog).
pub fn inline_svg(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_the_style_loads_nothing() {
        assert_eq!(
            escape("a<b & \"c\" 'd'"),
            "a&lt;b &amp; &quot;c&quot; &#39;d&#39;"
        );
        assert_eq!(inline_svg("<?xml?>\n<svg a>"), "<svg a>");
        assert!(!STYLE.contains("url(") && !STYLE.contains("@import"));
    }
}
