//! Checks of a plot's SVG by its text (for the tests, and for anyone who changes the
//! plots): every `<text>` element's box from its coordinates, anchor, baseline shift,
//! rotation and font size; whether two boxes overlap; which tick labels an axis has;
//! whether a legend entry is present. Pure: an SVG string in, findings out.
//!
//! A box is conservative: its width is 0.65 em a character (a monospace font's
//! advance is 0.60 em in a browser, 0.64 of the SVG's em in the PNG, whose layout the
//! SVG's coordinates come from), its height 1.24 em (the PNG's line height: plotters
//! writes the font size divided by 1.24).

/// Advance of one character, in em (see the module doc).
pub const CHAR_WIDTH_EM: f64 = 0.65;
/// Height of a line of text, in em.
pub const LINE_HEIGHT_EM: f64 = 1.24;

/// One `<text>` element: its content and the box it covers, px.
#[derive(Clone, Debug, PartialEq)]
pub struct TextBox {
    pub text: String,
    /// Left, top, right, bottom, px (y down).
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
    /// The anchor point (x, y attributes), px.
    pub at: (f64, f64),
    /// `text-anchor`: start, middle or end.
    pub anchor: String,
    /// Rotated by 90 or 270 degrees (an axis description).
    pub rotated: bool,
}

impl TextBox {
    /// Whether the two boxes share an area (touching edges do not count).
    pub fn overlaps(&self, other: &TextBox) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }
}

/// The value of attribute `name` in a tag's attribute text.
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let len = tag[start..].find('"')?;
    Some(&tag[start..start + len])
}

fn unescape(text: &str) -> String {
    text.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&#39;", "'")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// A length in em or ex (`0.76em`, `-0.5ex`) in em (1 ex = 0.5 em).
fn em(value: &str) -> Option<f64> {
    if let Some(v) = value.strip_suffix("em") {
        v.parse().ok()
    } else if let Some(v) = value.strip_suffix("ex") {
        v.parse::<f64>().ok().map(|v| 0.5 * v)
    } else {
        value.parse::<f64>().ok().map(|_| 0.0)
    }
}

/// The box of one `<text ...>content` element, or why it cannot be read.
fn text_box(tag: &str, content: &str) -> Result<TextBox, String> {
    let num = |name: &str| -> Result<f64, String> {
        attribute(tag, name)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("<text{tag}>: no numeric {name}"))
    };
    let (x, y, size) = (num("x")?, num("y")?, num("font-size")?);
    let text = unescape(content.trim());
    let w = text.chars().count() as f64 * CHAR_WIDTH_EM * size;
    let h = LINE_HEIGHT_EM * size;
    // the baseline shift plotters writes: 0.76em (top), 0.5ex (centre), -0.5ex (bottom)
    let dy = attribute(tag, "dy").and_then(em).unwrap_or(0.0);
    let top = if dy > 0.5 {
        0.0
    } else if dy > 0.0 {
        -0.5 * h
    } else {
        -h
    };
    let anchor = attribute(tag, "text-anchor").unwrap_or("start");
    let left = match anchor {
        "middle" => -0.5 * w,
        "end" => -w,
        _ => 0.0,
    };
    // corners relative to the anchor, rotated as the transform says
    let mut corners = [
        (left, top),
        (left + w, top),
        (left, top + h),
        (left + w, top + h),
    ];
    let transform = attribute(tag, "transform").unwrap_or("");
    let rotated = transform.starts_with("rotate(90") || transform.starts_with("rotate(270");
    for c in &mut corners {
        *c = if transform.starts_with("rotate(270") {
            (c.1, -c.0)
        } else if transform.starts_with("rotate(90") {
            (-c.1, c.0)
        } else if transform.starts_with("rotate(180") {
            (-c.0, -c.1)
        } else {
            *c
        };
    }
    let xs = corners.map(|c| x + c.0);
    let ys = corners.map(|c| y + c.1);
    Ok(TextBox {
        text,
        x0: xs.iter().copied().fold(f64::INFINITY, f64::min),
        x1: xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        y0: ys.iter().copied().fold(f64::INFINITY, f64::min),
        y1: ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        at: (x, y),
        anchor: anchor.to_string(),
        rotated,
    })
}

/// Every non-empty `<text>` element of `svg`, in document order.
pub fn text_boxes(svg: &str) -> Result<Vec<TextBox>, String> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find("<text") {
        rest = &rest[i + 5..];
        let close = rest.find('>').ok_or("an unclosed <text> tag")?;
        let tag = &rest[..close];
        let body = &rest[close + 1..];
        let end = body.find("</text>").ok_or("a <text> without </text>")?;
        if !body[..end].trim().is_empty() {
            out.push(text_box(tag, &body[..end])?);
        }
        rest = &body[end..];
    }
    Ok(out)
}

/// The pairs of text boxes that overlap.
pub fn overlapping(boxes: &[TextBox]) -> Vec<(TextBox, TextBox)> {
    let mut out = Vec::new();
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            if a.overlaps(b) {
                out.push((a.clone(), b.clone()));
            }
        }
    }
    out
}

/// The tick labels of the x axis and of the y axis, each sorted along its axis:
/// plotters centres an x label under its tick and right-aligns a y label left of its
/// tick, so the x labels are the centred texts sharing the most common baseline and
/// the y labels the right-aligned ones sharing the most common anchor x (the title,
/// the legend and the caption are neither).
pub fn axis_labels(boxes: &[TextBox]) -> (Vec<TextBox>, Vec<TextBox>) {
    let pick = |anchor: &str, key: &dyn Fn(&TextBox) -> f64, along: &dyn Fn(&TextBox) -> f64| {
        let cands: Vec<&TextBox> = boxes
            .iter()
            .filter(|b| !b.rotated && b.anchor == anchor)
            .collect();
        let count = |k: f64| cands.iter().filter(|c| (key(c) - k).abs() < 0.5).count();
        let Some(k) = cands.iter().map(|b| key(b)).max_by_key(|k| count(*k)) else {
            return Vec::new();
        };
        let mut v: Vec<TextBox> = cands
            .into_iter()
            .filter(|b| (key(b) - k).abs() < 0.5)
            .cloned()
            .collect();
        v.sort_by(|a, b| along(a).total_cmp(&along(b)));
        v
    };
    let x = pick("middle", &|b| b.at.1, &|b| b.at.0);
    let y = pick("end", &|b| b.at.0, &|b| -b.at.1);
    (x, y)
}

/// Whether `text` is a decade in engineering units: `0.1`, `1`, `10` or `100` (times a
/// prefix and unit, or a plain count like `1000`).
pub fn is_decade_label(text: &str) -> bool {
    let number = text.split(' ').next().unwrap_or("");
    let rest = &text[number.len()..];
    let unit_ok = rest.is_empty()
        || rest.strip_prefix(' ').is_some_and(|u| {
            ["s", "m", "J"].iter().any(|b| u.ends_with(b)) && u.chars().count() <= 2
        });
    let digits_ok = matches!(number, "0.1" | "1" | "10" | "100")
        || (number.starts_with('1') && number[1..].chars().all(|c| c == '0') && rest.is_empty());
    unit_ok && digits_ok
}

/// The decade labels of one axis in order must be one per decade: every label a
/// decade, none repeated, each next one the next decade (10 times the last). Returns
/// what is wrong, if anything; `value` reads a label's value.
pub fn decade_problems(labels: &[TextBox], value: impl Fn(&str) -> Option<f64>) -> Vec<String> {
    let mut problems = Vec::new();
    if labels.len() < 2 {
        problems.push(format!(
            "{} decade label(s): at least 2 expected",
            labels.len()
        ));
    }
    let values: Vec<Option<f64>> = labels.iter().map(|b| value(&b.text)).collect();
    for (b, v) in labels.iter().zip(&values) {
        if v.is_none() || !is_decade_label(&b.text) {
            problems.push(format!("`{}` is not a decade", b.text));
        }
    }
    for (w, t) in values.windows(2).zip(labels.windows(2)) {
        if let (Some(a), Some(b)) = (w[0], w[1]) {
            let ratio = b / a;
            if (ratio - 10.0).abs() > 1e-6 * 10.0 {
                problems.push(format!(
                    "`{}` then `{}`: not the next decade",
                    t[0].text, t[1].text
                ));
            }
        }
    }
    problems
}

/// The value of an engineering-unit label (`0.1 ms` -> 1e-4, `10 µm` -> 1e-5, `100`
/// -> 100).
pub fn label_value(text: &str) -> Option<f64> {
    let mut parts = text.split(' ');
    let number = parts.next()?;
    number.parse::<f64>().ok()?;
    let Some(unit) = parts.next() else {
        return number.parse().ok();
    };
    let prefix: String = unit
        .chars()
        .take(unit.chars().count().saturating_sub(1))
        .collect();
    let exponent = match prefix.as_str() {
        "" => 0,
        "k" => 3,
        "m" => -3,
        "µ" => -6,
        "n" => -9,
        "p" => -12,
        _ => return None,
    };
    // parsed from decimal text, so `10 µm` is exactly 1e-5
    format!("{number}e{exponent}").parse().ok()
}

/// The entries of `expected` no text of the SVG contains (texts joined in document
/// order by a space, so a legend entry wrapped over several lines is found whole).
pub fn missing_entries(boxes: &[TextBox], expected: &[&str]) -> Vec<String> {
    let all = boxes
        .iter()
        .map(|b| b.text.as_str())
        .collect::<Vec<_>>()
        .join(" ");
    expected
        .iter()
        .filter(|e| !all.contains(*e))
        .map(|e| e.to_string())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(x: f64, y: f64, anchor: &str, dy: &str, content: &str) -> String {
        format!(
            "<text x=\"{x}\" y=\"{y}\" dy=\"{dy}\" text-anchor=\"{anchor}\" \
             font-family=\"monospace\" font-size=\"11.29\" opacity=\"1\" \
             fill=\"#000000\">{content}</text>"
        )
    }

    #[test]
    fn boxes_follow_anchor_baseline_and_rotation() {
        let svg = text(100.0, 50.0, "middle", "0.76em", "10 ms");
        let b = &text_boxes(&svg).unwrap()[0];
        let w = 5.0 * CHAR_WIDTH_EM * 11.29;
        assert!((b.x0 - (100.0 - w / 2.0)).abs() < 1e-9 && (b.y0 - 50.0).abs() < 1e-9);
        let rotated = "<text x=\"20\" y=\"300\" dy=\"0.76em\" text-anchor=\"middle\" \
                       font-size=\"10\" transform=\"rotate(270, 20, 300)\">abcd</text>";
        let r = &text_boxes(rotated).unwrap()[0];
        assert!(r.rotated);
        // 4 characters along the (now vertical) line, one line across it
        assert!(
            (r.y1 - r.y0 - 4.0 * CHAR_WIDTH_EM * 10.0).abs() < 1e-9,
            "{r:?}"
        );
        assert!((r.x1 - r.x0 - LINE_HEIGHT_EM * 10.0).abs() < 1e-9, "{r:?}");
        assert_eq!(r.text, "abcd");
    }

    /// The negative test of the overlap check: labels 20 px apart overlap, 60 px do
    /// not.
    #[test]
    fn overlapping_labels_are_caught() {
        let close = [
            text(100.0, 500.0, "middle", "0.76em", "0.1 ms"),
            text(120.0, 500.0, "middle", "0.76em", "1 ms"),
        ]
        .concat();
        let boxes = text_boxes(&close).unwrap();
        assert_eq!(overlapping(&boxes).len(), 1);
        let apart = [
            text(100.0, 500.0, "middle", "0.76em", "0.1 ms"),
            text(160.0, 500.0, "middle", "0.76em", "1 ms"),
        ]
        .concat();
        assert!(overlapping(&text_boxes(&apart).unwrap()).is_empty());
    }

    /// The negative tests of the decade check: a missing decade, a repeated one and a
    /// label between decades are each caught.
    #[test]
    fn decades_must_follow_one_another() {
        let axis = |labels: &[&str]| -> Vec<TextBox> {
            let svg: String = labels
                .iter()
                .enumerate()
                .map(|(i, l)| text(100.0 + 80.0 * i as f64, 500.0, "middle", "0.76em", l))
                .collect();
            let boxes = text_boxes(&svg).unwrap();
            axis_labels(&boxes).0
        };
        let ok = axis(&["0.1 ms", "1 ms", "10 ms", "0.1 s"]);
        assert_eq!(ok.len(), 4);
        assert!(decade_problems(&ok, label_value).is_empty());
        let gap = axis(&["0.1 ms", "10 ms"]);
        assert_eq!(decade_problems(&gap, label_value).len(), 1);
        let twice = axis(&["1 ms", "1 ms", "10 ms"]);
        assert!(!decade_problems(&twice, label_value).is_empty());
        let between = axis(&["1 ms", "5 ms", "10 ms"]);
        assert!(decade_problems(&between, label_value)
            .iter()
            .any(|p| p.contains("`5 ms` is not a decade")));
        let old_style = axis(&["4.00e-4", "5.00e-4"]);
        assert!(decade_problems(&old_style, label_value).len() >= 2);
        assert!(!is_decade_label("5e-4"));
        assert!(!is_decade_label("2 ms"));
        assert!(is_decade_label("100 µm") && is_decade_label("1000"));
        assert_eq!(label_value("10 µm"), Some(1e-5));
        assert_eq!(label_value("0.1 ms"), Some(1e-4));
    }

    /// The negative test of the legend check: an entry no text contains is reported;
    /// one wrapped over two lines is found.
    #[test]
    fn a_missing_legend_entry_is_caught() {
        let svg = [
            text(
                700.0,
                60.0,
                "start",
                "0.76em",
                "chain (the default solver): dt",
            ),
            text(700.0, 78.0, "start", "0.76em", "sweep"),
            text(700.0, 100.0, "start", "0.76em", "lbfgsb: dt sweep"),
        ]
        .concat();
        let boxes = text_boxes(&svg).unwrap();
        assert!(missing_entries(&boxes, &["chain (the default solver): dt sweep"]).is_empty());
        assert_eq!(
            missing_entries(&boxes, &["lbfgsb", "Pareto front"]),
            vec!["Pareto front".to_string()]
        );
    }
}
