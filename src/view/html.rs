//! The self-contained HTML page: an interactive 3-D view of the toolpath
//! (the viewer's script and style are part of the binary, the scene's data
//! is inline), the statistics tables, the warnings and the travel-limit
//! violations. Nothing is loaded from elsewhere.

use serde::Serialize;

use super::plot::xml_escape;
use super::scene::{Scene, SceneData};
use super::stats::{Report, TimeReport, hms};
use crate::diag::Diagnostic;

const SCRIPT: &str = include_str!("assets/report.js");
const STYLE: &str = include_str!("assets/report.css");
const BODY: &str = include_str!("assets/report.html");

/// A warning as the page lists it.
#[derive(Debug, Serialize)]
struct PageWarning {
    code: &'static str,
    message: String,
    file: Option<String>,
    line: Option<u32>,
}

/// One axis's travel limits in work coordinates.
#[derive(Debug, Serialize)]
struct PageLimit {
    axis: usize,
    min: Option<f64>,
    max: Option<f64>,
    source: String,
}

#[derive(Debug, Serialize)]
struct PageData<'a> {
    program: &'a str,
    scene: SceneData,
    /// The work envelope: lowest and highest X, Y, Z over every move.
    envelope: Option<[[f64; 3]; 2]>,
    /// Travel limits moved into work coordinates with `offset`.
    limits: Vec<PageLimit>,
    offset: Option<[f64; 3]>,
    offset_varies: bool,
    warnings: Vec<PageWarning>,
    time: &'a TimeReport,
}

/// The page for `report` with the interactive view of `scene` and the
/// run's `warnings`.
pub(crate) fn page(report: &Report, scene: &Scene, warnings: &[Diagnostic]) -> String {
    let title = xml_escape(&report.program);
    let envelope = {
        let w = |i: usize| report.axes.iter().find(|a| a.axis == ["X", "Y", "Z"][i]);
        let r: Vec<_> = (0..3).filter_map(|i| w(i).and_then(|a| a.work)).collect();
        (r.len() == 3).then(|| {
            [
                [r[0].min, r[1].min, r[2].min],
                [r[0].max, r[1].max, r[2].max],
            ]
        })
    };
    let limits = report
        .limits
        .iter()
        .filter_map(|l| {
            let axis = ["X", "Y", "Z"].iter().position(|a| *a == l.axis)?;
            let off = scene.offset.map_or(0.0, |o| o[axis]);
            Some(PageLimit {
                axis,
                min: l.min.map(|v| v - off),
                max: l.max.map(|v| v - off),
                source: l.source.clone(),
            })
        })
        .collect();
    let data = PageData {
        program: &report.program,
        scene: scene.data(),
        envelope,
        limits,
        offset: scene.offset,
        offset_varies: scene.offset_varies,
        warnings: warnings
            .iter()
            .map(|d| {
                let at = d.site.as_ref().map(|s| {
                    let l = s.located();
                    (l.file, l.line)
                });
                PageWarning {
                    code: d.code(),
                    message: d.message(),
                    file: at.as_ref().map(|a| a.0.clone()),
                    line: at.map(|a| a.1),
                }
            })
            .collect(),
        time: &report.time,
    };
    // Inside a script element only "</" could end it early; "<\/" is the
    // same JSON string.
    let json = serde_json::to_string(&data)
        .unwrap_or_else(|_| "null".into())
        .replace("</", "<\\/")
        .replace('\u{2028}', "\\u2028")
        .replace('\u{2029}', "\\u2029");
    let mut s = String::with_capacity(json.len() + SCRIPT.len() + 16384);
    s.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    s.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    s.push_str(&format!("<title>{title} — toolpath</title>\n<style>\n"));
    s.push_str(STYLE);
    s.push_str("</style>\n</head>\n<body>\n");
    s.push_str(&BODY.replace("{{title}}", &title));
    s.push_str("<section id=\"tables\">\n");
    tables(&mut s, report);
    s.push_str("</section>\n");
    s.push_str("<script type=\"application/json\" id=\"ngcflat-data\">");
    s.push_str(&json);
    s.push_str("</script>\n<script>\n");
    s.push_str(SCRIPT);
    s.push_str("</script>\n</body>\n</html>\n");
    s
}

/// The time of one part of the run in words when it is not a plain
/// figure: none of it, or some moves not timed.
fn part_time(seconds: f64, moves: u64, untimed: u64, none: &str, why: &str) -> String {
    if moves == 0 {
        return none.to_string();
    }
    if untimed == 0 {
        return hms(seconds);
    }
    if untimed == moves {
        return format!("not timed ({}): {why}", plural(untimed, "move"));
    }
    format!(
        "{} for {}; {untimed} more not timed: {why}",
        hms(seconds),
        plural(moves - untimed, "move")
    )
}

fn plural(n: u64, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

fn tables(s: &mut String, report: &Report) {
    let num = |x: f64| crate::emit::number_string(x, Some(3));
    let cell = |v: Option<f64>| v.map_or("–".to_string(), num);
    s.push_str("<h2>Travel</h2>\n<table id=\"travel\">\n<tr><th>axis</th><th>work min</th><th>work max</th><th>machine min</th><th>machine max</th></tr>\n");
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
    if !report.limits.is_empty() {
        s.push_str("<h2>Travel limits</h2>\n<table id=\"limits\">\n<tr><th>axis</th><th>min</th><th>max</th><th>from</th><th>program</th></tr>\n");
        for l in &report.limits {
            let inside = match l.inside {
                Some(true) => "inside",
                Some(false) => "OUTSIDE",
                None => "not known",
            };
            s.push_str(&format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{inside}</td></tr>\n",
                l.axis,
                cell(l.min),
                cell(l.max),
                xml_escape(&l.source)
            ));
        }
        s.push_str("</table>\n");
    }
    s.push_str("<h2>Motion</h2>\n<table id=\"motion\">\n");
    let row = |k: &str, v: String| {
        format!(
            "<tr><td>{}</td><td>{}</td></tr>\n",
            xml_escape(k),
            xml_escape(&v)
        )
    };
    s.push_str(&row("moves", report.moves.to_string()));
    s.push_str(&row("rapid moves", report.rapid_moves.to_string()));
    s.push_str(&row("feed moves", report.feed_moves.to_string()));
    s.push_str(&row("arcs", report.arcs.to_string()));
    s.push_str(&row("probe moves", report.probe_moves.to_string()));
    s.push_str(&row("feed path (mm)", num(report.feed_length)));
    s.push_str(&row("rapid path (mm)", num(report.rapid_length)));
    s.push_str(&row("tool changes", report.tool_changes.to_string()));
    let tools: Vec<String> = report.tools.iter().map(|t| format!("T{t}")).collect();
    s.push_str(&row(
        "tools",
        if tools.is_empty() {
            "none named".into()
        } else {
            tools.join(", ")
        },
    ));
    s.push_str("</table>\n<h2>Time</h2>\n<table id=\"time\">\n");
    let t = &report.time;
    let untimed = t.untimed_feed_moves + t.untimed_rapid_moves;
    s.push_str(&row(
        "estimated time",
        if untimed == 0 {
            hms(t.total_s)
        } else {
            format!(
                "at least {} ({} not timed, see below)",
                hms(t.total_s),
                plural(untimed, "move")
            )
        },
    ));
    s.push_str(&row(
        "feed",
        part_time(
            t.feed_s,
            report.feed_moves,
            t.untimed_feed_moves,
            "no feed moves",
            "no feed rate, or feed per revolution with the spindle stopped",
        ),
    ));
    s.push_str(&row(
        "rapid",
        part_time(
            t.rapid_s,
            report.rapid_moves,
            t.untimed_rapid_moves,
            "no rapid moves",
            "their start is not known, or no maximum velocity was given for an axis they move",
        ),
    ));
    s.push_str(&row(
        "dwell",
        if t.dwell_s > 0.0 {
            hms(t.dwell_s)
        } else {
            "no dwells".into()
        },
    ));
    s.push_str("</table>\n");
    s.push_str(&format!(
        "<p class=\"model\">{} ({}). How the estimate is made: {}</p>\n",
        xml_escape(&t.model_name),
        xml_escape(&t.error),
        xml_escape(&t.model),
    ));
}
