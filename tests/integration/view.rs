//! Statistics, travel limits and the toolpath picture.
//!
//! The statistics are checked against rs274: a small reader here turns
//! rs274's canon of the same program (STRAIGHT_TRAVERSE, STRAIGHT_FEED,
//! ARC_FEED with the offsets and units it announces) into travel ranges and
//! path lengths, computed independently of ngcflat's geometry.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::oracle;

fn programs() -> PathBuf {
    crate::root().join("tests/integration/view-programs")
}

#[derive(Debug, Default)]
struct Canon {
    /// Ranges in mm over X, Y, Z: work and machine coordinates.
    work: [Option<(f64, f64)>; 3],
    machine: [Option<(f64, f64)>; 3],
    feed: f64,
    rapid: f64,
    moves: u64,
    arcs: u64,
}

fn grow(r: &mut Option<(f64, f64)>, v: f64) {
    *r = Some(match *r {
        Some((a, b)) => (a.min(v), b.max(v)),
        None => (v, v),
    });
}

fn args_of(line: &str) -> Vec<f64> {
    let inner = line
        .split_once('(')
        .and_then(|(_, r)| r.rsplit_once(')'))
        .map(|(a, _)| a)
        .unwrap_or("");
    inner
        .split([',', ' '])
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.trim().parse::<f64>().ok())
        .collect()
}

/// Reads rs274's canon lines (counter and N field already removed).
fn canon_stats(lines: &[String]) -> Canon {
    let mut c = Canon::default();
    let mut k = 1.0; // mm per program unit
    let mut plane = (0usize, 1usize, 2usize); // first, second, helix axis
    let mut g5x = [0.0; 3];
    let mut g92 = [0.0; 3];
    let mut tool = [0.0; 3];
    // Machine position (mm): the machine starts at its origin. Moves are
    // measured on the machine: a move that follows an offset change starts
    // where the machine is, in the new work coordinates.
    let mut pos_m = [0.0f64; 3];
    let mut first = true;
    let add_point = |c: &mut Canon, p: [f64; 3], off: [f64; 3]| {
        for i in 0..3 {
            grow(&mut c.work[i], p[i]);
            grow(&mut c.machine[i], p[i] + off[i]);
        }
    };
    for l in lines {
        let a = args_of(l);
        let off = |g5x: [f64; 3], g92: [f64; 3], tool: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|i| g5x[i] + g92[i] + tool[i])
        };
        if l.starts_with("USE_LENGTH_UNITS(") {
            k = if l.contains("INCHES") { 25.4 } else { 1.0 };
        } else if l.starts_with("SELECT_PLANE(") {
            plane = if l.contains("XZ") {
                (2, 0, 1)
            } else if l.contains("YZ") {
                (1, 2, 0)
            } else {
                (0, 1, 2)
            };
        } else if l.starts_with("SET_G5X_OFFSET(") {
            g5x = [a[1] * k, a[2] * k, a[3] * k];
        } else if l.starts_with("SET_G92_OFFSET(") {
            g92 = [a[0] * k, a[1] * k, a[2] * k];
        } else if l.starts_with("USE_TOOL_LENGTH_OFFSET(") {
            tool = [a[0] * k, a[1] * k, a[2] * k];
        } else if l.starts_with("STRAIGHT_TRAVERSE(") || l.starts_with("STRAIGHT_FEED(") {
            let o = off(g5x, g92, tool);
            let start: [f64; 3] = std::array::from_fn(|i| pos_m[i] - o[i]);
            let end = [a[0] * k, a[1] * k, a[2] * k];
            if first {
                add_point(&mut c, start, o);
                first = false;
            }
            add_point(&mut c, end, o);
            let len = ((end[0] - start[0]).powi(2)
                + (end[1] - start[1]).powi(2)
                + (end[2] - start[2]).powi(2))
            .sqrt();
            if l.starts_with("STRAIGHT_TRAVERSE") {
                c.rapid += len;
            } else {
                c.feed += len;
            }
            c.moves += 1;
            pos_m = std::array::from_fn(|i| end[i] + o[i]);
        } else if l.starts_with("ARC_FEED(") {
            let o = off(g5x, g92, tool);
            let start: [f64; 3] = std::array::from_fn(|i| pos_m[i] - o[i]);
            if first {
                add_point(&mut c, start, o);
                first = false;
            }
            let (fa, fb, h) = plane;
            let mut end = [0.0; 3];
            end[fa] = a[0] * k;
            end[fb] = a[1] * k;
            end[h] = a[5] * k;
            let (ca, cb) = (a[2] * k, a[3] * k);
            let rot = a[4];
            let r = (start[fa] - ca).hypot(start[fb] - cb);
            let a0 = (start[fb] - cb).atan2(start[fa] - ca);
            let a1 = (end[fb] - cb).atan2(end[fa] - ca);
            let tau = std::f64::consts::TAU;
            let turns = rot.abs() - 1.0;
            // Swept angle, positive, in the direction of rotation.
            let mut sweep = if rot > 0.0 { a1 - a0 } else { a0 - a1 };
            while sweep <= 1e-12 {
                sweep += tau;
            }
            sweep += turns * tau;
            // Every multiple of 90 degrees passed on the way.
            for q in 0..4 {
                let ang = q as f64 * std::f64::consts::FRAC_PI_2;
                let mut d = if rot > 0.0 { ang - a0 } else { a0 - ang };
                while d < 0.0 {
                    d += tau;
                }
                while d >= tau {
                    d -= tau;
                }
                if d > 0.0 && d < sweep {
                    let mut p = start;
                    p[fa] = ca + r * ang.cos();
                    p[fb] = cb + r * ang.sin();
                    p[h] = start[h] + (end[h] - start[h]) * d / sweep;
                    add_point(&mut c, p, o);
                }
            }
            add_point(&mut c, end, o);
            c.feed += ((r * sweep).powi(2) + (end[h] - start[h]).powi(2)).sqrt();
            c.moves += 1;
            c.arcs += 1;
            pos_m = std::array::from_fn(|i| end[i] + o[i]);
        }
    }
    c
}

fn rs274_canon(program: &Path, tools: Option<&Path>) -> Vec<String> {
    let dir = tempfile::tempdir().expect("tempdir");
    let ini = dir.path().join("v.ini");
    std::fs::write(&ini, "[RS274NGC]\n").expect("ini");
    let mut cmd = Command::new(oracle::RS274);
    cmd.current_dir(dir.path()).env("HOME", dir.path());
    cmd.arg("-g").arg("-i").arg(&ini);
    if let Some(t) = tools {
        cmd.arg("-t").arg(t);
    }
    cmd.arg(program)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let out = cmd.output().expect("run rs274");
    assert!(out.status.success(), "rs274 fails on {}", program.display());
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let t = l.trim_start();
            let d = t.bytes().take_while(u8::is_ascii_digit).count();
            let rest = t.get(d..)?.strip_prefix(" N")?;
            Some(
                rest.trim_start_matches(|c: char| c == '.' || c.is_ascii_digit())
                    .trim()
                    .to_string(),
            )
        })
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 1e-9
}

fn stats_json(program: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<String> = vec!["stats".into(), "--json".into(), "--zero-start".into()];
    args.extend(extra.iter().map(|s| s.to_string()));
    args.push(program.display().to_string());
    let (code, out, err) = crate::outcome(crate::ngcflat(&programs(), &args, None));
    assert_eq!(code, 0, "stats {}: {err}", program.display());
    serde_json::from_str(&out).expect("stats --json is JSON")
}

fn compare_with_rs274(name: &str, tools: bool) {
    if !oracle::available(&format!("view::{name}")) {
        return;
    }
    let prog = programs().join(name);
    let tbl = programs().join("tools.tbl");
    let canon = rs274_canon(&prog, tools.then_some(tbl.as_path()));
    let c = canon_stats(&canon);
    assert!(c.moves > 0, "no motion in rs274's canon of {name}");
    let extra: Vec<&str> = if tools {
        vec!["--tool-table", "tools.tbl"]
    } else {
        vec![]
    };
    let j = stats_json(&prog, &extra);
    let mut problems = Vec::new();
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    for (key, want) in [("feed_length", c.feed), ("rapid_length", c.rapid)] {
        let got = num(&j[key]);
        if !close(got, want) {
            problems.push(format!("{key}: ngcflat {got}, rs274 {want}"));
        }
    }
    if j["moves"].as_u64() != Some(c.moves) || j["arcs"].as_u64() != Some(c.arcs) {
        problems.push(format!(
            "moves/arcs: ngcflat {}/{}, rs274 {}/{}",
            j["moves"], j["arcs"], c.moves, c.arcs
        ));
    }
    let axes = j["axes"].as_array().cloned().unwrap_or_default();
    for (i, letter) in ["X", "Y", "Z"].iter().enumerate() {
        let a = axes.iter().find(|a| a["axis"] == *letter);
        let Some(a) = a else {
            problems.push(format!("{letter}: missing from ngcflat's axes"));
            continue;
        };
        for (frame, want) in [("work", c.work[i]), ("machine", c.machine[i])] {
            let Some((lo, hi)) = want else { continue };
            let (glo, ghi) = (num(&a[frame]["min"]), num(&a[frame]["max"]));
            if !close(glo, lo) || !close(ghi, hi) {
                problems.push(format!(
                    "{letter} {frame}: ngcflat {glo}..{ghi}, rs274 {lo}..{hi}"
                ));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "{name}: stats disagree with rs274's canon:\n  {}",
        problems.join("\n  ")
    );
}

#[test]
fn stats_match_rs274_arcs_crossing_quadrants() {
    compare_with_rs274("arcs-quadrants.ngc", false);
}

#[test]
fn stats_match_rs274_inch_program() {
    compare_with_rs274("inch.ngc", false);
}

#[test]
fn stats_match_rs274_work_offsets() {
    compare_with_rs274("work-offsets.ngc", false);
}

#[test]
fn stats_match_rs274_tool_length_offsets() {
    compare_with_rs274("tool-length.ngc", true);
}

#[test]
fn canon_reader_finds_arc_extremes() {
    // The reader itself: a clockwise half circle from (10,0) to (-10,0)
    // about the origin passes (0,-10).
    let lines: Vec<String> = [
        "STRAIGHT_TRAVERSE(10.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
        "ARC_FEED(-10.0000, 0.0000, 0.0000, 0.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let c = canon_stats(&lines);
    assert_eq!(c.work[1], Some((-10.0, 0.0)));
    assert_eq!(c.work[0], Some((-10.0, 10.0)));
    assert!(close(c.feed, 10.0 * std::f64::consts::PI));
}

#[test]
fn bad_machine_options_are_usage_errors() {
    let dir = crate::tmp();
    crate::put(dir.path(), "p.ngc", "G0 X1\nM2\n");
    crate::put(dir.path(), "grbl.txt", "$0=10\n$110=fast\n");
    crate::put(dir.path(), "m.ini", "[AXIS_Z]\nMAX_LIMIT = high\n");
    for (args, want) in [
        (
            vec!["--limits", "X5", "p.ngc"],
            "error[E1201]: --limits 'X5' is not a list of AXIS[MIN]:[MAX] ranges",
        ),
        (
            vec!["--limits", "X10:0", "p.ngc"],
            "error[E1201]: --limits 'X10:0'",
        ),
        (
            vec!["check", "--limits", "Q0:1", "p.ngc"],
            "error[E1201]: --limits 'Q0:1'",
        ),
        (
            vec!["--grbl-settings", "grbl.txt", "p.ngc"],
            "error[E1202]: GRBL $110 value 'fast' is not a number",
        ),
        (
            vec!["stats", "--ini", "m.ini", "p.ngc"],
            "error[E1202]: INI [AXIS_Z]MAX_LIMIT value 'high' is not a number",
        ),
    ] {
        let (code, out, err) = crate::run(dir.path(), &args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(out.is_empty());
        assert!(err.contains(want), "{args:?}: {err}");
    }
}

/// The installed headless browser, if any.
fn chromium() -> Option<PathBuf> {
    ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .iter()
        .map(PathBuf::from)
        .find(|p| p.exists())
}

/// Pixels of a PNG that differ from its top-left (background) colour, and
/// how many distinct colours those have.
fn non_background(png_path: &Path) -> (usize, usize) {
    let file = std::fs::File::open(png_path).expect("screenshot");
    let mut dec = png::Decoder::new(std::io::BufReader::new(file));
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("png size")];
    let info = reader.next_frame(&mut buf).expect("png frame");
    let ch = info.color_type.samples();
    let px: Vec<&[u8]> = buf[..info.buffer_size()].chunks(ch).collect();
    let bg = px[0];
    let mut colours = std::collections::HashSet::new();
    let mut n = 0;
    for p in &px {
        if *p != bg {
            n += 1;
            colours.insert(p.to_vec());
        }
    }
    (n, colours.len())
}

/// Renders pictures of a few programs in a real headless browser and
/// checks they are not blank. Skips (and says so) without Chromium.
#[test]
fn plots_render_in_a_browser() {
    let Some(browser) = chromium() else {
        assert!(
            !crate::webdriver::required(),
            "view::plots_render_in_a_browser: chromium is required but not installed"
        );
        eprintln!(
            "SKIPPED view::plots_render_in_a_browser: no chromium (apt-get install -y chromium)"
        );
        return;
    };
    let out = crate::tmp();
    for (prog, view) in [
        (crate::root().join("fixtures/ok/example-pocket.ngc"), "xy"),
        (programs().join("arcs-quadrants.ngc"), "iso"),
        (programs().join("arcs-quadrants.ngc"), "xz"),
        (programs().join("inch.ngc"), "xy"),
    ] {
        let stem = prog
            .file_stem()
            .expect("stem")
            .to_string_lossy()
            .into_owned();
        let svg = out.path().join(format!("{stem}-{view}.svg"));
        let (code, _, err) = crate::run(
            out.path(),
            &[
                "plot",
                "--zero-start",
                "--view",
                view,
                "-o",
                svg.to_str().expect("utf-8 path"),
                prog.to_str().expect("utf-8 path"),
            ],
        );
        assert_eq!(code, 0, "plot {stem} {view}: {err}");
        let png = out.path().join(format!("{stem}-{view}.png"));
        let profile = crate::tmp();
        let status = Command::new(&browser)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                "--hide-scrollbars",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg(format!("--screenshot={}", png.display()))
            .arg("--window-size=1100,800")
            .arg(&svg)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .expect("run chromium");
        assert!(status.success(), "chromium failed on {}", svg.display());
        let (ink, colours) = non_background(&png);
        // The toolpath, the box, the labels: thousands of pixels in
        // several colours (a blank or all-black page has none).
        assert!(
            ink > 3000 && colours > 3,
            "{stem} ({view}): {ink} non-background pixels in {colours} colours"
        );
        if let Ok(dir) = std::env::var("NGCFLAT_KEEP_SCREENSHOTS") {
            let _ = std::fs::copy(&png, Path::new(&dir).join(png.file_name().expect("name")));
        }
    }
}

#[test]
fn annotated_output_keeps_rs274_motion_and_messages() {
    if !oracle::available("view::annotated_output_keeps_rs274_motion_and_messages") {
        return;
    }
    let dir = crate::tmp();
    crate::put(
        dir.path(),
        "subs/edge.ngc",
        "o<edge> sub\n  G1 X#1 (MSG, edge)\n  (debug, at #1)\no<edge> endsub\nM2\n",
    );
    let main = "G21 G90 F300\nG0 X0 Y0\no<edge> call [5]\no<edge> call [7]\n(MSG, done)\nG2 X9 Y2 I1 J1\nM2\n";
    crate::put(dir.path(), "main.ngc", main);
    let (code, out, err) = crate::run(
        dir.path(),
        &["--zero-start", "-I", "subs", "--annotate", "main.ngc"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("G1 X5 (MSG, edge) ;from subs/edge.ngc:2:1 < main.ngc:3:1"),
        "{out}"
    );
    let ini = oracle::ini_with(&[dir.path().join("subs")], "");
    let a = oracle::run(main.as_bytes(), &ini, None);
    let b = oracle::run(out.as_bytes(), &oracle::ini_with(&[], ""), None);
    assert!(a.ok && b.ok, "{} / {}", a.stderr, b.stderr);
    assert!(a.lines.iter().any(|l| l.contains("MESSAGE(\" edge\")")));
    oracle::compare(&a.lines, &b.lines, 1e-4).expect("same canon with --annotate");
}

#[test]
fn source_map_has_a_line_per_output_line() {
    let dir = crate::tmp();
    crate::put(
        dir.path(),
        "subs/sq.ngc",
        "o<sq> sub\nG1 X#1\nG1 Y#1\no<sq> endsub\nM2\n",
    );
    crate::put(
        dir.path(),
        "main.ngc",
        "G21 F100\no1 repeat [2]\n  o<sq> call [3]\no1 endrepeat\nM2\n",
    );
    let (code, out, err) = crate::run(
        dir.path(),
        &[
            "--zero-start",
            "-I",
            "subs",
            "--source-map",
            "map.jsonl",
            "main.ngc",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let map = std::fs::read_to_string(dir.path().join("map.jsonl")).expect("source map written");
    let entries: Vec<serde_json::Value> = map
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect();
    assert_eq!(entries.len(), out.lines().count(), "{out}\n{map}");
    // Output: G21 F100, then G1 X3, G1 Y3 twice, then M2.
    let e = &entries[3];
    assert_eq!(e["output_line"], 4);
    assert_eq!(e["file"], "subs/sq.ngc");
    assert_eq!(e["line"], 2);
    assert_eq!(e["calls"][0]["file"], "main.ngc");
    assert_eq!(e["calls"][0]["line"], 3);
    assert_eq!(e["calls"][0]["column"], 3);
    assert_eq!(entries[5]["line"], 5);
    assert_eq!(entries[5]["calls"].as_array().map(Vec::len), Some(0));
    // A program that fails leaves no source map behind.
    crate::put(dir.path(), "bad.ngc", "G1 X[1/0]\nM2\n");
    let (code, _, _) = crate::run(
        dir.path(),
        &["--zero-start", "--source-map", "bad.jsonl", "bad.ngc"],
    );
    assert_eq!(code, 1);
    assert!(!dir.path().join("bad.jsonl").exists());
}

#[test]
fn check_stops_at_the_travel_limit() {
    let dir = crate::tmp();
    crate::put(dir.path(), "ok.ngc", "G21 G0 X10 Y10\nG1 X90 F100\nM2\n");
    crate::put(
        dir.path(),
        "far.ngc",
        "G21 G0 X10 Y10\nG1 X110 F100\nG1 X200\nM2\n",
    );
    let (code, _, err) = crate::run(
        dir.path(),
        &["check", "--zero-start", "--limits", "X0:100,Y0:100", "."],
    );
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("far.ngc:2:1"), "{err}");
    assert!(err.contains("[E1203]") || err.contains("E1203"), "{err}");
    assert!(!err.contains("ok.ngc:"), "{err}");
    // --no-limits turns it off.
    let (code, _, err) = crate::run(
        dir.path(),
        &[
            "check",
            "--zero-start",
            "--limits",
            "X0:100",
            "--no-limits",
            ".",
        ],
    );
    assert_eq!(code, 0, "{err}");
}

#[test]
fn run_time_estimate_uses_grbl_rates_and_accelerations() {
    let dir = crate::tmp();
    // X: 100 mm/s (6000 mm/min), 50 mm/s²; Y: 25 mm/s, 10 mm/s².
    crate::put(
        dir.path(),
        "grbl.txt",
        "$110=6000.000\n$111=1500.000\n$112=600\n$120=50.000\n$121=10\n$122=10\n",
    );
    // A 200 mm rapid along X, a 5 mm rapid along Y, then a 100 mm feed
    // along X at F1200 (20 mm/s) and a 1 s dwell.
    crate::put(
        dir.path(),
        "p.ngc",
        "G21 G90 G94\nG0 X200\nG0 Y5\nG1 X100 F1200\nG4 P1\nM2\n",
    );
    let (code, out, err) = crate::run(
        dir.path(),
        &[
            "stats",
            "--json",
            "--zero-start",
            "--grbl-settings",
            "grbl.txt",
            "p.ngc",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).expect("json");
    // GRBL's planner, the other settings GRBL's defaults ($11 = 0.01 mm
    // junction deviation, $1 = 25 ms idle delay). Both corners are 90°:
    // the junction's direction (-1, ±1)/√2 allows min(50, 10)·√2 =
    // 14.142 mm/s²; v² = 14.142·0.01·sin45°/(1 − sin45°) = 0.34142.
    let vj2: f64 = 10.0 * 2f64.sqrt() * 0.01 * 0.5f64.sqrt() / (1.0 - 0.5f64.sqrt());
    let vj = vj2.sqrt();
    // X200 at 100 mm/s, 50 mm/s² from rest to vj: cruises for
    // 200 − 100 − (100² − vj²)/100 mm.
    let x = 2.0 + (100.0 - vj) / 50.0 + (200.0 - 100.0 - (1e4 - vj2) / 100.0) / 100.0;
    // Y5 at 10 mm/s² from vj to vj never reaches 25 mm/s: a triangle
    // peaking at sqrt((2·10·5 + 2·vj²)/2).
    let peak = ((100.0 + 2.0 * vj2) / 2.0f64).sqrt();
    let y = 2.0 * (peak - vj) / 10.0;
    // X100 at F1200 (20 mm/s), 50 mm/s², from vj to rest.
    let up = (400.0 - vj2) / 100.0;
    let feed = (20.0 - vj) / 50.0 + 0.4 + (100.0 - up - 4.0) / 20.0;
    let rapid = x + y;
    let t = &j["time"];
    assert!(close(t["rapid_s"].as_f64().unwrap_or(0.0), rapid), "{t}");
    assert!(close(t["feed_s"].as_f64().unwrap_or(0.0), feed), "{t}");
    assert!(close(t["dwell_s"].as_f64().unwrap_or(0.0), 1.0), "{t}");
    // The dwell empties the buffer: one full stop and its 25 ms; M2 finds
    // the machine at rest.
    assert!(close(t["wait_s"].as_f64().unwrap_or(0.0), 0.025), "{t}");
    assert_eq!(t["stops"], 1);
    assert!(
        close(t["total_s"].as_f64().unwrap_or(0.0), rapid + feed + 1.025),
        "{t}"
    );
    assert_eq!(t["machine_limits_used"], true);
    // GRBL's envelope was not given ($130-$132 absent): no limits.
    let (code, text, err) = crate::run(
        dir.path(),
        &[
            "stats",
            "--zero-start",
            "--grbl-settings",
            "grbl.txt",
            "p.ngc",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        text.contains("by the GRBL 1.1h planner (within 0.1%"),
        "{text}"
    );
}

#[test]
fn stats_without_known_offsets_leave_machine_coordinates_out() {
    let dir = crate::tmp();
    crate::put(
        dir.path(),
        "p.ngc",
        "G21 G90\nG0 X1 Y2 Z3\nG1 X4 F100\nM2\n",
    );
    let (code, text, err) = crate::run(dir.path(), &["stats", "p.ngc"]);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("machine coordinates unknown"), "{text}");
    let (_, json, _) = crate::run(dir.path(), &["stats", "--json", "p.ngc"]);
    let j: serde_json::Value = serde_json::from_str(&json).expect("json");
    assert_eq!(j["machine_known"], false);
    assert!(j["axes"][0]["machine"].is_null());
    assert_eq!(j["axes"][0]["work"]["max"], 4.0);
}

#[test]
fn html_page_is_self_contained() {
    let dir = crate::tmp();
    crate::put(
        dir.path(),
        "p.ngc",
        "(a <test> & more)\nG21 G90 F100\nT3 M6\nG0 X10 Y0\nG2 X0 Y10 I-10 J0\nM2\n",
    );
    // Without --zero-start the first rapid's start is not known: it is
    // not timed.
    let (code, _, err) = crate::run(dir.path(), &["plot", "-o", "p.html", "p.ngc"]);
    assert_eq!(code, 0, "{err}");
    let html = std::fs::read_to_string(dir.path().join("p.html")).expect("page written");
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains("<canvas id=\"view\""));
    assert!(html.contains("<td>arcs</td><td>1</td>"), "{html}");
    assert!(html.contains("<td>tools</td><td>T3</td>"), "{html}");
    assert!(html.contains("How the estimate is made"));
    // The program's name is escaped wherever it appears.
    assert!(!html.contains("<test>"), "unescaped program text");
    // No external resources: no element loads anything, no script fetches.
    for bad in [
        "<link",
        "src=",
        "href=",
        "url(",
        "@import",
        "fetch(",
        "XMLHttpRequest",
        "import(",
        "http:",
        "https:",
    ] {
        assert!(!html.contains(bad), "{bad} in the page");
    }
    // Untimed parts are said in words, never a bare zero.
    assert!(
        html.contains("<tr><td>rapid</td><td>not timed (1 move)"),
        "{html}"
    );
    assert!(!html.contains("0:00:00.0</td>"), "{html}");
    // The picture never replaces the program.
    let (code, _, err) = crate::run(
        dir.path(),
        &["plot", "--zero-start", "-o", "p.ngc", "p.ngc"],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("E0702"), "{err}");
    assert!(
        std::fs::read_to_string(dir.path().join("p.ngc")).is_ok_and(|t| t.starts_with("(a <test>"))
    );
    // An unwritable output is an I/O error (exit 2) and writes nothing.
    let (code, _, err) = crate::run(
        dir.path(),
        &["plot", "--zero-start", "-o", "no/such/dir/p.svg", "p.ngc"],
    );
    assert_eq!(code, 2, "{err}");
}

/// Programs whose motion the machine model does not follow yet (cutter
/// compensation, canned cycles, G28/G53 moves, NURBS, spirals measured by
/// their mean radius) or where rs274's 4 printed decimals of inches differ
/// by more than the tolerance.
const SWEEP_SKIP: &[&str] = &[
    "comp/",
    "lathe-cycles/",
    "cycle-repeat-reuses-r-and-depth",
    "position/cycle-",
    "g10-p-rounding",
    "g80-with-other-motion-code",
    "m73-auto-restore",
    "g5-3-moves-to-last-point",
    "g5-2-order-on-a-point-line",
    "center-arc-radius-within-tolerance",
    "g28-home-position",
    "g43-1-with-motion-moves",
    "g53-g28-with-tool-offset",
];

/// Every `fixtures/ok` program without extra arguments: `stats --json`
/// agrees with rs274's canon on path lengths, move counts and work ranges
/// within 1e-4 relative (rs274 prints 4 decimals).
#[test]
fn stats_of_every_fixture_match_rs274() {
    if !oracle::available("view::stats_of_every_fixture_match_rs274") {
        return;
    }
    let root = crate::root().join("fixtures/ok");
    let mut checked = 0;
    let mut problems = Vec::new();
    for e in walkdir::WalkDir::new(&root).sort_by_file_name() {
        let Ok(e) = e else { continue };
        let p = e.path();
        let rel = p
            .strip_prefix(&root)
            .unwrap_or(p)
            .to_string_lossy()
            .into_owned();
        if p.extension().is_none_or(|x| x != "ngc")
            || rel.contains("subs/")
            || p.with_extension("args").exists()
            || SWEEP_SKIP.iter().any(|s| rel.contains(s))
        {
            continue;
        }
        let canon = {
            let dir = tempfile::tempdir().expect("tempdir");
            let ini = dir.path().join("v.ini");
            std::fs::write(&ini, "[RS274NGC]\n").expect("ini");
            let out = Command::new(oracle::RS274)
                .current_dir(dir.path())
                .env("HOME", dir.path())
                .arg("-g")
                .arg("-i")
                .arg(&ini)
                .arg(p)
                .stdin(Stdio::null())
                .output()
                .expect("rs274");
            if !out.status.success() {
                continue;
            }
            String::from_utf8_lossy(&out.stdout)
                .lines()
                .filter_map(|l| {
                    let t = l.trim_start();
                    let d = t.bytes().take_while(u8::is_ascii_digit).count();
                    let rest = t.get(d..)?.strip_prefix(" N")?;
                    Some(
                        rest.trim_start_matches(|c: char| c == '.' || c.is_ascii_digit())
                            .trim()
                            .to_string(),
                    )
                })
                .collect::<Vec<_>>()
        };
        let c = canon_stats(&canon);
        let args: Vec<String> = vec![
            "stats".into(),
            "--json".into(),
            "--zero-start".into(),
            p.display().to_string(),
        ];
        let (code, out, _) =
            crate::outcome(crate::ngcflat(p.parent().unwrap_or(&root), &args, None));
        if code != 0 {
            continue;
        }
        let Ok(j) = serde_json::from_str::<serde_json::Value>(&out) else {
            problems.push(format!("{rel}: stats --json is not JSON"));
            continue;
        };
        checked += 1;
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1.0);
        let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
        if !near(num(&j["feed_length"]), c.feed) || !near(num(&j["rapid_length"]), c.rapid) {
            problems.push(format!(
                "{rel}: lengths feed {} rapid {}, rs274 {} {}",
                j["feed_length"], j["rapid_length"], c.feed, c.rapid
            ));
        }
        if j["moves"].as_u64() != Some(c.moves) {
            problems.push(format!("{rel}: {} moves, rs274 {}", j["moves"], c.moves));
        }
        let axes = j["axes"].as_array().cloned().unwrap_or_default();
        for (i, letter) in ["X", "Y", "Z"].iter().enumerate() {
            let Some((lo, hi)) = c.work[i] else { continue };
            let a = axes.iter().find(|a| a["axis"] == *letter);
            let (glo, ghi) = a.map_or((f64::NAN, f64::NAN), |a| {
                (num(&a["work"]["min"]), num(&a["work"]["max"]))
            });
            if !near(glo, lo) || !near(ghi, hi) {
                problems.push(format!("{rel}: {letter} {glo}..{ghi}, rs274 {lo}..{hi}"));
            }
        }
    }
    assert!(checked > 100, "only {checked} fixtures compared");
    assert!(
        problems.is_empty(),
        "{} of {checked} fixtures disagree with rs274:\n  {}",
        problems.len(),
        problems.join("\n  ")
    );
}

#[test]
fn limits_hold_for_target_output() {
    let dir = crate::tmp();
    crate::put(
        dir.path(),
        "p.ngc",
        "G21 G90 G17 F100\nG0 X10 Y10\nG1 X150\nM2\n",
    );
    // The limit check looks at the program's motion whatever the target.
    let (code, out, err) = crate::run(
        dir.path(),
        &[
            "--target",
            "grbl",
            "--zero-start",
            "--limits",
            "X0:100",
            "p.ngc",
        ],
    );
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty());
    assert!(err.contains("E1203") && err.contains("p.ngc:3:1"), "{err}");
    let (code, out, err) = crate::run(
        dir.path(),
        &[
            "--target",
            "grbl",
            "--zero-start",
            "--limits",
            "X0:200",
            "p.ngc",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("G1 X150"), "{out}");
    let (code, _, err) = crate::run(
        dir.path(),
        &[
            "check",
            "--target",
            "grbl",
            "--zero-start",
            "--limits",
            "X0:100",
            "p.ngc",
        ],
    );
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("E1203"), "{err}");
}

/// With a target, the source map and `--annotate` describe the lines the
/// controller gets (a canned cycle's moves each mapped to the cycle's
/// line; the M0 a tool change becomes, to the M6), timed by the target's
/// planner: the lines' times add up to what `stats` says, and a file
/// name's bytes GRBL would act on never reach the output.
#[test]
fn source_maps_and_annotations_follow_the_target_s_lines() {
    let dir = crate::tmp();
    let prog = "G21 G90 G17 F600\nT1 M6\nG0 X10 Y10 Z5\nG81 X20 Y10 Z-2 R1\nX30\nG80\nG1 X50 Y40\nG4 P0.12\nM2\n";
    crate::put(dir.path(), "p!?.ngc", prog);
    let base = ["--target", "grbl", "--zero-start", "p!?.ngc"];
    let (code, plain, err) = crate::run(dir.path(), &base);
    assert_eq!(code, 0, "{err}");
    let mut args = vec!["--annotate", "--source-map", "m.jsonl"];
    args.extend(base);
    let (code, out, err) = crate::run(dir.path(), &args);
    assert_eq!(code, 0, "{err}");
    let map = std::fs::read_to_string(dir.path().join("m.jsonl")).expect("source map written");
    let entries: Vec<serde_json::Value> = map
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect();
    // The same lines as without the options, each with its comment.
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), plain.lines().count(), "{out}");
    assert_eq!(entries.len(), lines.len(), "{map}");
    for (l, p) in lines.iter().zip(plain.lines()) {
        let (code, note) = l.split_once(" ;from ").unwrap_or((l, ""));
        assert_eq!(code, p);
        assert!(note.is_empty() || note.starts_with("p__.ngc:"), "{l}");
        assert!(!note.contains(['!', '?', '~']), "{l}");
    }
    // The drilling cycle's moves all come from line 4, the M0 from line 2.
    let from = |line: u64| entries.iter().filter(|e| e["line"] == line).count();
    assert!(from(4) > 3, "{map}");
    let m0 = lines
        .iter()
        .position(|l| l.starts_with("M0"))
        .expect("an M0");
    assert_eq!(entries[m0]["line"], 2, "{map}");
    // Times: in order, adding up to the total of `stats` for the target.
    let mut t = 0.0;
    for e in &entries {
        let (start, dt) = (e["t"].as_f64().expect("t"), e["dt"].as_f64().expect("dt"));
        assert!((start - t).abs() < 1e-5, "{e}");
        t = start + dt;
    }
    let (_, json, _) = crate::run(
        dir.path(),
        &[
            "stats",
            "--json",
            "--target",
            "grbl",
            "--zero-start",
            "p!?.ngc",
        ],
    );
    let j: serde_json::Value = serde_json::from_str(&json).expect("json");
    let total = j["time"]["total_s"].as_f64().expect("total");
    assert!((t - total).abs() < 1e-4, "{t} against {total}");
    // The dwell's line takes GRBL's 0.15 s and the stop's 25 ms.
    let dwell = lines
        .iter()
        .position(|l| l.starts_with("G4"))
        .expect("a G4");
    assert!(
        (entries[dwell]["dt"].as_f64().unwrap_or(0.0) - 0.175).abs() < 1e-6,
        "{map}"
    );
}

#[test]
fn stats_report_the_travel_limits_instead_of_stopping() {
    let dir = crate::tmp();
    crate::put(
        dir.path(),
        "p.ngc",
        "G21 G90 G17 F100\nG0 X10 Y45\nG2 X30 Y45 I10 J0\nM2\n",
    );
    let (code, out, err) = crate::run(
        dir.path(),
        &[
            "stats",
            "--json",
            "--zero-start",
            "--limits",
            "X0:100,Y0:50",
            "p.ngc",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).expect("json");
    let l = j["limits"].as_array().cloned().unwrap_or_default();
    assert_eq!(l.len(), 2, "{out}");
    assert_eq!(
        (l[0]["axis"].as_str(), l[0]["inside"].as_bool()),
        (Some("X"), Some(true))
    );
    // The arc's top is at Y55.
    assert_eq!(
        (l[1]["axis"].as_str(), l[1]["inside"].as_bool()),
        (Some("Y"), Some(false))
    );
    assert_eq!(l[1]["source"], "--limits");
    let (_, text, _) = crate::run(dir.path(), &["stats", "--limits", "Y0:50", "p.ngc"]);
    assert!(
        text.contains("limit Y 0.000..50.000 from --limits: not known"),
        "{text}"
    );
}

/// An INI given for its subroutine path and switches does not make
/// flattening check its travel limits (which would need the machine's
/// offsets): only --ini-limits does.
#[test]
fn ini_limits_are_checked_only_when_asked() {
    let dir = crate::tmp();
    crate::put(
        dir.path(),
        "m.ini",
        "[TRAJ]\nLINEAR_UNITS = mm\n[AXIS_X]\nMIN_LIMIT = 0\nMAX_LIMIT = 10\n",
    );
    crate::put(dir.path(), "p.ngc", "G21 G90\nG0 X50 Y1\nM2\n");
    // Offsets unknown, limits not asked for: flattens.
    let (code, out, err) = crate::run(dir.path(), &["--ini", "m.ini", "p.ngc"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("G0 X50 Y1"), "{out}");
    // Known offsets, limits not asked for: flattens.
    let (code, _, err) = crate::run(dir.path(), &["--ini", "m.ini", "--zero-start", "p.ngc"]);
    assert_eq!(code, 0, "{err}");
    // Asked for: the move leaves the envelope.
    let (code, out, err) = crate::run(
        dir.path(),
        &["--ini", "m.ini", "--zero-start", "--ini-limits", "p.ngc"],
    );
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty());
    assert!(err.contains("E1203"), "{err}");
    assert!(err.contains("p.ngc:2:"), "{err}");
    // Asked for without known offsets: the error names the options.
    let (code, _, err) = crate::run(dir.path(), &["--ini", "m.ini", "--ini-limits", "p.ngc"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("E1204"), "{err}");
}

/// A feed far above what any axis can do (3D_Chips.ngc scales its feeds
/// by 10000) runs at the machine's limit, not in no time: with no INI at
/// LinuxCNC's own defaults for an INI that gives none (1 mm/s, 1 mm/s²),
/// said next to the figure; with an INI at its MAX_VELOCITY and
/// MAX_ACCELERATION.
#[test]
fn a_feed_above_the_machine_runs_at_its_limits() {
    let dir = crate::tmp();
    crate::put(dir.path(), "p.ngc", "G21 G90\nG1 X100 F1000000\nM2\n");
    crate::put(
        dir.path(),
        "m.ini",
        "[TRAJ]\nLINEAR_UNITS = mm\nCOORDINATES = XYZ\n[AXIS_X]\nMAX_VELOCITY = 10\nMAX_ACCELERATION = 100\n",
    );
    let total = |args: &[&str]| {
        let (code, json, err) = crate::run(dir.path(), args);
        assert_eq!(code, 0, "{err}");
        let j: serde_json::Value = serde_json::from_str(&json).expect("json");
        j["time"]["total_s"].as_f64().expect("a total")
    };
    // 100 mm at 1 mm/s with 1 mm/s²: 1 s and 0.5 mm up, the same down,
    // 99 mm at 1 mm/s: 101 s (the programmed feed alone: 0.006 s).
    let t = total(&["stats", "--json", "--zero-start", "p.ngc"]);
    assert!((t - 101.0).abs() < 1e-9, "{t}");
    // At 10 mm/s and 100 mm/s²: 0.1 s and 0.5 mm up, the same down, 99 mm
    // in 9.9 s: 10.1 s.
    let t = total(&["stats", "--json", "--zero-start", "--ini", "m.ini", "p.ngc"]);
    assert!((t - 10.1).abs() < 1e-9, "{t}");
    let (_, text, _) = crate::run(dir.path(), &["stats", "--zero-start", "p.ngc"]);
    assert!(
        text.contains(
            "by the LinuxCNC 2.9 trajectory planner (a model: against LinuxCNC's simulator"
        ),
        "{text}"
    );
    assert!(
        text.contains("no --ini: LinuxCNC's default limits"),
        "{text}"
    );
    assert!(!text.contains("no machine velocity"), "{text}");
}

/// GRBL empties its buffer whenever a line selects another coordinate
/// system or sets G92 or G10 offsets, even to the values in effect
/// (`systems.ngc` switches G54, G55, G56 with every offset 0): a full stop
/// and its 25 ms wait each, which the estimate counts.
#[test]
fn grbl_stops_at_every_offset_setting() {
    let dir = crate::tmp();
    let stops = |prog: &str| {
        crate::put(dir.path(), "p.ngc", prog);
        let (code, json, err) = crate::run(
            dir.path(),
            &[
                "stats",
                "--json",
                "--zero-start",
                "--target",
                "grbl",
                "p.ngc",
            ],
        );
        assert_eq!(code, 0, "{err}");
        let j: serde_json::Value = serde_json::from_str(&json).expect("json");
        (j["time"]["stops"].as_u64(), j["time"]["wait_s"].as_f64())
    };
    // One stop at the end.
    let (n, w) = stops("G21 G90\nG1 X10 F300\nG1 X20 Y5\nM2\n");
    assert_eq!((n, w), (Some(1), Some(0.025)));
    // G55 (offsets all 0), G92 X0 at X20 after the stop, G55 again (no
    // change: no stop), G10 L2 P3 (an inactive system, written to EEPROM).
    let (n, _) = stops(
        "G21 G90\nG1 X10 F300\nG55\nG1 X20 Y5\nG92 X0\nG1 X5\nG55 G1 X6\nG10 L2 P3 X0\nG1 X8\nM2\n",
    );
    assert_eq!(n, Some(4));
}

/// The report page's timeline puts each move where the run-time model puts
/// its line: with GRBL's 15-block look-ahead a move's time is known only
/// blocks later, and the page's start and duration of every move are those
/// of its output line in the source map.
#[test]
fn the_page_s_timeline_follows_each_line_s_planned_time() {
    use base64::Engine;
    let dir = crate::tmp();
    let mut prog = String::from("G21 G90 F1000\nG0 X10 Y0\n");
    for i in 1..=60 {
        let a = f64::from(i) * std::f64::consts::TAU / 60.0;
        prog.push_str(&format!(
            "G1 X{:.4} Y{:.4}\n",
            10.0 * a.cos(),
            10.0 * a.sin()
        ));
    }
    prog.push_str("M2\n");
    crate::put(dir.path(), "p.ngc", &prog);
    let common = ["--target", "grbl", "--zero-start"];
    let mut args = vec!["--source-map", "m.jsonl"];
    args.extend(common);
    args.push("p.ngc");
    let (code, _, err) = crate::run(dir.path(), &args);
    assert_eq!(code, 0, "{err}");
    let map: Vec<serde_json::Value> = std::fs::read_to_string(dir.path().join("m.jsonl"))
        .expect("map")
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect();
    let mut args = vec!["plot", "-o", "p.html"];
    args.extend(common);
    args.push("p.ngc");
    let (code, _, err) = crate::run(dir.path(), &args);
    assert_eq!(code, 0, "{err}");
    let html = std::fs::read_to_string(dir.path().join("p.html")).expect("page");
    let json = html
        .split("<script type=\"application/json\" id=\"ngcflat-data\">")
        .nth(1)
        .and_then(|s| s.split("</script>").next())
        .expect("the page's data");
    let data: serde_json::Value = serde_json::from_str(json).expect("data");
    let arr = |k: &str| {
        base64::engine::general_purpose::STANDARD
            .decode(data["scene"][k].as_str().expect(k))
            .expect("base64")
    };
    let t0: Vec<f64> = arr("t0")
        .chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    let dur: Vec<f32> = arr("dur")
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    let line: Vec<u32> = arr("line")
        .chunks(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    assert_eq!(t0.len(), 61, "a move per line");
    for k in 0..t0.len() {
        let e = &map[line[k] as usize - 1];
        let (t, dt) = (e["t"].as_f64().expect("t"), e["dt"].as_f64().expect("dt"));
        assert!((t0[k] - t).abs() < 1e-5, "move {k}: {} against {t}", t0[k]);
        assert!(
            (f64::from(dur[k]) - dt).abs() < 1e-5,
            "move {k}: {} against {dt}",
            dur[k]
        );
    }
    // The last chords run at the look-ahead's pace, not in no time.
    assert!(dur[30] > 0.01, "{}", dur[30]);
}

/// `stats --no-time` leaves the run-time estimate out and says so.
#[test]
fn stats_without_the_time() {
    let dir = crate::tmp();
    crate::put(dir.path(), "p.ngc", "G21 G90\nG1 X100 F600\nM2\n");
    let (code, text, err) =
        crate::run(dir.path(), &["stats", "--zero-start", "--no-time", "p.ngc"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.contains("estimated time: not estimated (--no-time)"),
        "{text}"
    );
    assert!(text.contains("path: feed 100.000 mm"), "{text}");
    let (_, json, _) = crate::run(
        dir.path(),
        &["stats", "--json", "--zero-start", "--no-time", "p.ngc"],
    );
    let j: serde_json::Value = serde_json::from_str(&json).expect("json");
    assert_eq!(j["time"]["total_s"], 0.0);
    assert_eq!(j["time"]["model_name"], "none");
}
