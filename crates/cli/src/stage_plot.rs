//! `frepray bench --plot FILE.svg`: the CPU's and the GPU's stage times as stacked
//! horizontal bars, one per measured render (the paper's Fig. 4–5 layout: the share of each pipeline stage in
//! a frame).

use std::fmt::Write;
use std::time::Duration;

/// One bar: its label and its stages (name, time).
pub type Bar = (String, Vec<(&'static str, Duration)>);

const COLOURS: [&str; 12] = [
    "#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1", "#ff9da7",
    "#9c755f", "#bab0ac", "#86bcb6", "#d37295",
];

/// The SVG of `bars`, each scaled to its own total (shares, in per cent), with a legend
/// and each bar's total time written beside it. A stage keeps its colour across bars
/// (CPU and GPU bars have different stages); the legend names each stage once.
pub fn svg(title: &str, bars: &[Bar]) -> String {
    let mut names: Vec<&str> = Vec::new();
    for (_, stages) in bars {
        for (name, _) in stages {
            if !names.contains(name) {
                names.push(name);
            }
        }
    }
    let colour = |name: &str| {
        let k = names.iter().position(|n| *n == name).unwrap_or(0);
        COLOURS[k % COLOURS.len()]
    };
    let (w, left, bar_h, gap) = (760.0, 220.0, 26.0, 14.0);
    let top = 50.0;
    let legend_y = top + bars.len() as f64 * (bar_h + gap) + 10.0;
    // Legend entries, wrapped into rows that fit the width.
    let mut legend = Vec::new();
    let (mut x, mut row) = (10.0, 0.0);
    for name in &names {
        let width = 24.0 + 7.0 * name.chars().count() as f64;
        if x + width > w && x > 10.0 {
            (x, row) = (10.0, row + 20.0);
        }
        legend.push((x, legend_y + row, *name));
        x += width;
    }
    let h = legend_y + row + 40.0;
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
        for (name, d) in stages {
            let share = if total > 0.0 {
                d.as_secs_f64() / total
            } else {
                0.0
            };
            let bw = share * span;
            let _ = writeln!(
                s,
                r#"<rect x="{x:.1}" y="{y:.1}" width="{bw:.1}" height="{bar_h}" fill="{}"><title>{}: {:.1} ms ({:.1} %)</title></rect>"#,
                colour(name),
                escape(name),
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
    for (x, y, name) in legend {
        let _ = writeln!(
            s,
            r#"<rect x="{x}" y="{y}" width="12" height="12" fill="{}"/><text x="{}" y="{}">{}</text>"#,
            colour(name),
            x + 16.0,
            y + 10.0,
            escape(name)
        );
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

    /// A stage has one colour in every bar and one legend entry, whatever the bars hold.
    #[test]
    fn stages_keep_their_colour_across_bars() {
        let ms = Duration::from_millis;
        let bars = vec![
            ("cpu".to_string(), vec![("x", ms(1)), ("shade", ms(2))]),
            ("gpu".to_string(), vec![("shade", ms(3)), ("z", ms(4))]),
        ];
        let s = svg("t", &bars);
        let fill = |name: &str| {
            let at = s.find(&format!("<title>{name}:")).unwrap();
            let head = &s[..at];
            let f = head.rfind("fill=\"").unwrap();
            head[f + 6..f + 13].to_string()
        };
        let shade: Vec<_> = s.match_indices("<title>shade:").collect();
        assert_eq!(shade.len(), 2);
        assert_eq!(fill("shade"), COLOURS[1]);
        assert_eq!(fill("z"), COLOURS[2]);
        assert_eq!(s.matches(">shade</text>").count(), 1);
    }
}
