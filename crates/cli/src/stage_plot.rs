//! `frepray bench --plot FILE.svg`: the GPU's stage times as stacked horizontal bars, one
//! per measured render (the paper's Fig. 4–5 layout: the share of each pipeline stage in
//! a frame).

use std::fmt::Write;
use std::time::Duration;

/// One bar: its label and its stages (name, time).
pub type Bar = (String, Vec<(&'static str, Duration)>);

const COLOURS: [&str; 6] = [
    "#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948",
];

/// The SVG of `bars`, each scaled to its own total (shares, in per cent), with a legend
/// and each bar's total time written beside it.
pub fn svg(title: &str, bars: &[Bar]) -> String {
    let (w, left, bar_h, gap) = (760.0, 220.0, 26.0, 14.0);
    let top = 50.0;
    let legend_y = top + bars.len() as f64 * (bar_h + gap) + 10.0;
    let h = legend_y + 40.0;
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">
<text x="10" y="22" font-size="15">{title}</text>
"#
    );
    let span = w - left - 90.0;
    for (i, (label, stages)) in bars.iter().enumerate() {
        let y = top + i as f64 * (bar_h + gap);
        let total: f64 = stages.iter().map(|s| s.1.as_secs_f64()).sum();
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#,
            left - 8.0,
            y + bar_h * 0.65,
            escape(label)
        );
        let mut x = left;
        for (k, (name, d)) in stages.iter().enumerate() {
            let share = if total > 0.0 {
                d.as_secs_f64() / total
            } else {
                0.0
            };
            let bw = share * span;
            let _ = writeln!(
                s,
                r#"<rect x="{x:.1}" y="{y:.1}" width="{bw:.1}" height="{bar_h}" fill="{}"><title>{name}: {:.1} ms ({:.1} %)</title></rect>"#,
                COLOURS[k % COLOURS.len()],
                d.as_secs_f64() * 1e3,
                100.0 * share
            );
            x += bw;
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{}">{:.2} s</text>"#,
            left + span + 6.0,
            y + bar_h * 0.65,
            total
        );
    }
    if let Some((_, stages)) = bars.first() {
        let mut x = 10.0;
        for (k, (name, _)) in stages.iter().enumerate() {
            let _ = writeln!(
                s,
                r#"<rect x="{x}" y="{legend_y}" width="12" height="12" fill="{}"/><text x="{}" y="{}">{}</text>"#,
                COLOURS[k % COLOURS.len()],
                x + 16.0,
                legend_y + 10.0,
                escape(name)
            );
            x += 24.0 + 7.0 * name.chars().count() as f64;
        }
    }
    s + "</svg>\n"
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each bar's stages fill its width in proportion; the legend names every stage.
    #[test]
    fn bars_are_shares_of_their_total() {
        let ms = Duration::from_millis;
        let bars = vec![
            ("a".to_string(), vec![("x", ms(30)), ("y", ms(10))]),
            ("b <2>".to_string(), vec![("x", ms(5)), ("y", ms(15))]),
        ];
        let s = svg("t", &bars);
        let span = 760.0 - 220.0 - 90.0;
        assert!(s.contains(&format!(r#"width="{:.1}""#, 0.75 * span)));
        assert!(s.contains(&format!(r#"width="{:.1}""#, 0.25 * span)));
        assert!(s.contains("b &lt;2&gt;"));
        assert!(s.contains(">x</text>") && s.contains(">y</text>"));
        assert!(s.starts_with("<svg") && s.ends_with("</svg>\n"));
    }
}
