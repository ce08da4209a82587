//! The self-contained HTML page: the toolpath picture and the statistics.

use super::plot::xml_escape;
use super::stats::{Report, hms};

/// A page holding `svg` inline and the statistics of `report`; no external
/// resources.
pub(crate) fn page(svg: &str, report: &Report) -> String {
    let mut s = String::with_capacity(svg.len() + 8192);
    let title = xml_escape(&report.program);
    s.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    s.push_str(&format!("<title>{title} — toolpath</title>\n"));
    s.push_str(
        "<style>body{font-family:sans-serif;margin:1.5em;color:#222}\
         table{border-collapse:collapse;margin:0.5em 0}\
         td,th{border:1px solid #ccc;padding:0.2em 0.6em;text-align:right}\
         th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}\
         .svg{overflow:auto;border:1px solid #ddd;display:inline-block}\
         p.model{max-width:60em;color:#555;font-size:0.9em}</style>\n</head>\n<body>\n",
    );
    s.push_str(&format!("<h1>{title}</h1>\n<div class=\"svg\">\n"));
    s.push_str(svg);
    s.push_str("</div>\n<h2>Travel</h2>\n<table>\n<tr><th>axis</th><th>work min</th><th>work max</th><th>machine min</th><th>machine max</th></tr>\n");
    let cell = |v: Option<f64>| {
        v.map_or("–".to_string(), |x| {
            crate::emit::number_string(x, Some(3))
        })
    };
    for a in &report.axes {
        s.push_str(&format!(
            "<tr><td>{} ({})</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            a.axis,
            a.unit,
            cell(a.work.map(|r| r.min)),
            cell(a.work.map(|r| r.max)),
            cell(a.machine.map(|r| r.min)),
            cell(a.machine.map(|r| r.max)),
        ));
    }
    s.push_str("</table>\n");
    if !report.machine_known {
        s.push_str("<p>Machine coordinates are not known: the offsets from work to machine coordinates were not given (--zero-start, --var-file or -D).</p>\n");
    }
    s.push_str("<h2>Motion</h2>\n<table>\n");
    let row = |k: &str, v: String| format!("<tr><td>{k}</td><td>{}</td></tr>\n", xml_escape(&v));
    s.push_str(&row("moves", report.moves.to_string()));
    s.push_str(&row("rapid moves", report.rapid_moves.to_string()));
    s.push_str(&row("feed moves", report.feed_moves.to_string()));
    s.push_str(&row("arcs", report.arcs.to_string()));
    s.push_str(&row(
        "feed path (mm)",
        crate::emit::number_string(report.feed_length, Some(3)),
    ));
    s.push_str(&row(
        "rapid path (mm)",
        crate::emit::number_string(report.rapid_length, Some(3)),
    ));
    s.push_str(&row("tool changes", report.tool_changes.to_string()));
    let tools: Vec<String> = report.tools.iter().map(|t| format!("T{t}")).collect();
    s.push_str(&row("tools", tools.join(", ")));
    let t = &report.time;
    s.push_str(&row("estimated time", hms(t.total_s)));
    s.push_str(&row("  feed", hms(t.feed_s)));
    s.push_str(&row("  rapid", hms(t.rapid_s)));
    s.push_str(&row("  dwell", hms(t.dwell_s)));
    s.push_str("</table>\n");
    s.push_str(&format!(
        "<p class=\"model\">How the estimate is made: {}{}</p>\n",
        xml_escape(t.model),
        if t.machine_limits_used {
            ""
        } else {
            " No machine velocity or acceleration limits were given (--ini, --grbl-settings)."
        }
    ));
    s.push_str("</body>\n</html>\n");
    s
}
