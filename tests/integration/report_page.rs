//! The interactive HTML report, driven in headless Chromium through
//! WebDriver: it loads without a console error, draws every move of the
//! flattened output, shows the source line and call chain of a clicked
//! move, hides what the Z slider and the rapids switch say, and its
//! timeline ends at the estimated total time. What the page is checked
//! against is worked out here from ngcflat's flattened output and source
//! map, not from the page.

use std::path::Path;

use serde_json::{Value, json};

use crate::webdriver::{self, Driver};

/// One move of the flattened output, read by a small reader of its own:
/// absolute coordinates, G0-G3 on the line or modal from an earlier one.
#[derive(Debug, Clone)]
struct FlatMove {
    rapid: bool,
    z0: f64,
    z1: f64,
}

fn words(line: &str) -> Vec<(char, f64)> {
    // Comments off: ( ... ) and ; to the end.
    let mut s = String::new();
    let mut depth = 0;
    for c in line.chars() {
        match c {
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            ';' if depth == 0 => break,
            c if depth == 0 => s.push(c),
            _ => {}
        }
    }
    let s: String = s.chars().filter(|c| !c.is_whitespace()).collect();
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let letter = (b[i] as char).to_ascii_uppercase();
        let mut j = i + 1;
        while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.' || b[j] == b'-' || b[j] == b'+')
        {
            j += 1;
        }
        if let Ok(v) = s[i + 1..j].parse::<f64>() {
            out.push((letter, v));
        }
        i = j.max(i + 1);
    }
    out
}

/// Moves of a flat program written in G21 G90 with X, Y, Z only.
fn flat_moves(flat: &str) -> Vec<FlatMove> {
    let mut pos = [0.0f64; 3];
    let mut motion: Option<u8> = None;
    let mut out = Vec::new();
    for line in flat.lines() {
        let w = words(line);
        for &(l, v) in &w {
            if l == 'G' && [0.0, 1.0, 2.0, 3.0].contains(&v) {
                motion = Some(v as u8);
            }
            assert!(
                !(l == 'G' && [20.0, 91.0, 81.0, 82.0, 83.0, 38.2].contains(&v)),
                "the test's reader does not do G{v}: {line}"
            );
        }
        let mut to = pos;
        let mut axis = false;
        for &(l, v) in &w {
            if let Some(a) = "XYZ".find(l) {
                to[a] = v;
                axis = true;
            }
        }
        if let (true, Some(m)) = (axis, motion) {
            out.push(FlatMove {
                rapid: m == 0,
                z0: pos[2],
                z1: to[2],
            });
            pos = to;
        }
    }
    out
}

/// h:mm:ss.s as the page and `stats` write it.
fn hms(s: f64) -> String {
    let tenths = (s * 10.0).round() as u64;
    let (h, rest) = (tenths / 36000, tenths % 36000);
    format!(
        "{h}:{:02}:{:02}.{}",
        rest / 600,
        (rest % 600) / 10,
        rest % 10
    )
}

fn severe(log: &[Value]) -> Vec<String> {
    log.iter()
        .filter(|e| e["level"] == "SEVERE")
        .map(|e| e["message"].to_string())
        .collect()
}

fn text_of(d: &Driver, id: &str) -> String {
    d.eval(
        "const e = document.getElementById(arguments[0]); return e ? e.textContent : null;",
        json!([id]),
    )
    .as_str()
    .unwrap_or_else(|| panic!("no element #{id}"))
    .to_string()
}

/// Sets a range input as a user's drag would leave it (its value, then the
/// input event the page listens to).
fn slide(d: &Driver, id: &str, value: u32) {
    d.eval(
        "const e = document.getElementById(arguments[0]); e.value = arguments[1]; e.dispatchEvent(new Event('input', {bubbles: true}));",
        json!([id, value]),
    );
}

fn write_program(dir: &Path) {
    crate::put(
        dir,
        "subs/layer.ngc",
        "o<layer> sub\n\
         (one pass of the pocket at depth #1)\n\
         G1 Z#1 F100\n\
         G1 X30 F400\n\
         G3 X30 Y20 I0 J10\n\
         G1 X0\n\
         G1 Y0\n\
         o<layer> endsub\nM2\n",
    );
    crate::put(
        dir,
        "main.ngc",
        "G21 G90 G17 G94\n\
         T1 M6\n\
         G0 Z5\n\
         G0 X0 Y0\n\
         #<z> = -0.7\n\
         o100 while [#<z> GE -2.9]\n\
           o<layer> call [#<z>]\n\
           #<z> = [#<z> - 1]\n\
         o100 endwhile\n\
         G0 Z5\n\
         T2 M6\n\
         G0 X50 Y-10\n\
         G1 Z-1 F80\n\
         G1 X55 Y-5 Z-1.5 F[120 + #3000]\n\
         G0 Z5\n\
         G0 X110 Y0\n\
         M2\n",
    );
}

#[test]
fn report_page_in_chromium() {
    let Some(d) = webdriver::start_or_skip("report_page::report_page_in_chromium") else {
        return;
    };
    let dir = crate::tmp();
    write_program(dir.path());
    let common = [
        "--zero-start",
        "-I",
        "subs",
        "--limits",
        "X-5:100,Y-20:40,Z-10:10",
    ];
    let run = |extra: &[&str]| {
        let args: Vec<&str> = extra.iter().chain(common.iter()).copied().collect();
        crate::run(dir.path(), &args)
    };
    let (code, _, err) = run(&["plot", "-o", "p.html", "main.ngc"]);
    assert_eq!(code, 0, "plot: {err}");
    // The flattened program, its source map and its statistics are what the
    // page is checked against. Limits off: the flattening would stop at
    // the move that leaves them.
    let (code, flat, err) = crate::run(
        dir.path(),
        &[
            "--zero-start",
            "-I",
            "subs",
            "--source-map",
            "p.map",
            "main.ngc",
        ],
    );
    assert_eq!(code, 0, "flatten: {err}");
    let map: Vec<Value> = std::fs::read_to_string(dir.path().join("p.map"))
        .expect("source map")
        .lines()
        .map(|l| serde_json::from_str(l).expect("map line"))
        .collect();
    let (code, stats, err) = crate::run(
        dir.path(),
        &["stats", "--json", "--zero-start", "-I", "subs", "main.ngc"],
    );
    assert_eq!(code, 0, "stats: {err}");
    let stats: Value = serde_json::from_str(&stats).expect("stats json");
    let moves = flat_moves(&flat);
    let flat_lines: Vec<&str> = flat.lines().collect();
    let case = Case {
        d: &d,
        moves: &moves,
        flat_lines: &flat_lines,
        map: &map,
        stats: &stats,
    };
    d.open(&dir.path().join("p.html"));
    let log = d.log();
    assert!(
        severe(&log).is_empty(),
        "console errors: {:?}",
        severe(&log)
    );

    // Every move of the output is in the scene.
    let n = d.eval("return ngcflat.moves;", json!([]));
    assert_eq!(n.as_u64(), Some(moves.len() as u64), "moves in the scene");
    assert_eq!(
        d.eval("return ngcflat.shown();", json!([])).as_u64(),
        Some(moves.len() as u64)
    );

    case.click_shows_source();
    case.sliders_and_switches();
    case.timeline();
    case.links();

    // Turning the view with the mouse changes the picture; the page stays
    // free of errors through it all.
    d.eval("ngcflat.setView('iso');", json!([]));
    let before = d.screenshot();
    d.drag((300.0, 400.0), (420.0, 330.0));
    let after = d.screenshot();
    assert_ne!(before, after, "dragging turns the view");
    let log = d.log();
    assert!(
        severe(&log).is_empty(),
        "console errors: {:?}",
        severe(&log)
    );
}

/// What the page is checked against.
struct Case<'a> {
    d: &'a Driver,
    moves: &'a [FlatMove],
    flat_lines: &'a [&'a str],
    map: &'a [Value],
    stats: &'a Value,
}

impl Case<'_> {
    /// Clicking a move inside the subroutine shows its output line, its
    /// source line and the call that made it.
    fn click_shows_source(&self) {
        let (d, map, flat_lines) = (self.d, self.map, self.flat_lines);
        let target = map
            .iter()
            .find(|e| {
                e["file"].as_str().is_some_and(|f| f.ends_with("layer.ngc"))
                    && e["line"] == 4
                    && !e["calls"].as_array().expect("calls").is_empty()
            })
            .expect("a move made in the subroutine");
        let out_line = target["output_line"].as_u64().expect("output line");
        let k = d.eval(
            "ngcflat.setView('top'); return ngcflat.moveOfLine(arguments[0]);",
            json!([out_line]),
        );
        let k = k.as_i64().expect("move index");
        assert!(k >= 0, "output line {out_line} has a move in the scene");
        let p = d.eval("return ngcflat.screenPoint(arguments[0]);", json!([k]));
        let (x, y) = (p[0].as_f64().expect("x"), p[1].as_f64().expect("y"));
        d.click_at(x, y);
        let sel = d.eval("return ngcflat.selected();", json!([]));
        let picked = sel[0].as_i64().expect("a move is selected");
        // The top view shows the passes of the pocket on top of each other: the
        // click selects one of them, all made by the same source line.
        let picked_line = d
            .eval("return ngcflat.lineOf(arguments[0]);", json!([picked]))
            .as_u64()
            .expect("line");
        let picked_map = &map[picked_line as usize - 1];
        assert_eq!(picked_map["file"], target["file"]);
        assert_eq!(picked_map["line"], 4);
        let file = target["file"].as_str().expect("file");
        assert_eq!(text_of(d, "src-loc"), format!("{file}:4"));
        let call = &picked_map["calls"][0];
        assert_eq!(
            text_of(d, "src-chain"),
            format!("{}:{}", call["file"].as_str().expect("file"), call["line"])
        );
        assert_eq!(
            text_of(d, "out-text"),
            flat_lines[picked_line as usize - 1],
            "the output line's text"
        );
    }

    fn sliders_and_switches(&self) {
        let (d, moves) = (self.d, self.moves);
        // The Z slider: with the highest Z at 70 % of the range, exactly the
        // moves that reach below it stay.
        let zlo = moves
            .iter()
            .map(|m| m.z0.min(m.z1))
            .fold(f64::INFINITY, f64::min);
        let zhi = moves
            .iter()
            .map(|m| m.z0.max(m.z1))
            .fold(f64::NEG_INFINITY, f64::max);
        let cut = zlo + (zhi - zlo) * 0.7;
        slide(d, "zhi", 700);
        let expect = moves.iter().filter(|m| m.z0.min(m.z1) <= cut).count();
        assert!(expect < moves.len() && expect > 0);
        let shown = d
            .eval("return ngcflat.visibleMoves().length;", json!([]))
            .as_u64();
        assert_eq!(shown, Some(expect as u64), "moves below Z {cut}");
        // Now also above the lowest pass only: the passes below -1 stay.
        slide(d, "zlo", 300);
        let cut_lo = zlo + (zhi - zlo) * 0.3;
        let expect = moves
            .iter()
            .filter(|m| m.z0.min(m.z1) <= cut && m.z0.max(m.z1) >= cut_lo)
            .count();
        let shown = d
            .eval("return ngcflat.visibleMoves().length;", json!([]))
            .as_u64();
        assert_eq!(
            shown,
            Some(expect as u64),
            "moves between Z {cut_lo} and {cut}"
        );
        slide(d, "zlo", 0);
        slide(d, "zhi", 1000);

        // Rapids off: the feed moves stay.
        d.eval("document.getElementById('show-rapids').click();", json!([]));
        let feeds = moves.iter().filter(|m| !m.rapid).count();
        let shown = d
            .eval("return ngcflat.visibleMoves().length;", json!([]))
            .as_u64();
        assert_eq!(shown, Some(feeds as u64), "feed moves");
        d.eval("document.getElementById('show-rapids').click();", json!([]));
    }

    fn timeline(&self) {
        let (d, stats) = (self.d, self.stats);
        // The timeline at its end shows the total time and nothing remaining;
        // half way it shows half of it.
        let total = stats["time"]["total_s"].as_f64().expect("total time");
        assert!(total > 1.0, "{stats}");
        slide(d, "time", 50_000);
        assert_eq!(text_of(d, "elapsed"), hms(total / 2.0));
        assert!(text_of(d, "current").starts_with("Executing: output line "));
        slide(d, "time", 100_000);
        assert_eq!(text_of(d, "elapsed"), hms(total));
        assert_eq!(text_of(d, "remaining"), hms(0.0));
    }

    fn links(&self) {
        let (d, flat_lines) = (self.d, self.flat_lines);
        // The move that leaves the travel limits (X110) is listed, and its link
        // selects it.
        let links = d.eval(
            "return [...document.querySelectorAll('#violations a')].map(a => a.textContent);",
            json!([]),
        );
        let viol_line = flat_lines
            .iter()
            .position(|l| l.contains("X110"))
            .expect("the X110 move")
            + 1;
        let links = links.as_array().expect("links");
        assert_eq!(links.len(), 1, "{links:?}");
        assert!(
            links[0]
                .as_str()
                .is_some_and(|t| t.starts_with(&format!("output line {viol_line}:"))),
            "{links:?}"
        );
        d.eval(
            "document.querySelector('#violations a').click();",
            json!([]),
        );
        let sel = d.eval(
            "return ngcflat.selected().map(k => ngcflat.lineOf(k));",
            json!([]),
        );
        assert_eq!(sel, json!([viol_line]));

        // The warning (#3000 read before it was set) links to its move.
        let warn = d.eval(
        "const a = document.querySelector('#warnings a'); if (!a) return null; a.click(); return [a.textContent, ngcflat.selected().map(k => ngcflat.lineOf(k))];",
        json!([]),
    );
        let warn_line = flat_lines
            .iter()
            .position(|l| l.contains("X55"))
            .expect("the X55 move")
            + 1;
        assert_eq!(warn[1], json!([warn_line]), "{warn}");
    }
}

/// `plot --open` hands the written page, by its absolute path, to the
/// desktop's opener (here a stand-in `xdg-open` first on PATH).
#[cfg(all(unix, not(target_os = "macos")))]
#[test]
fn plot_open_starts_the_desktop_opener() {
    use std::os::unix::fs::PermissionsExt;
    let dir = crate::tmp();
    crate::put(dir.path(), "p.ngc", "G21 G90 F100\nG1 X10 Y5\nM2\n");
    let bin = dir.path().join("bin");
    let seen = dir.path().join("opened.txt");
    crate::put(
        dir.path(),
        "bin/xdg-open",
        &format!("#!/bin/sh\nprintf '%s' \"$1\" > '{}'\n", seen.display()),
    );
    std::fs::set_permissions(bin.join("xdg-open"), std::fs::Permissions::from_mode(0o755))
        .expect("chmod");
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let plot = |open: bool, out: &str| {
        let mut args = vec!["plot", "--zero-start", "-o", out, "p.ngc"];
        if open {
            args.insert(1, "--open");
        }
        std::process::Command::new(crate::bin())
            .current_dir(dir.path())
            .env("PATH", &path)
            .env_remove("WSL_DISTRO_NAME")
            .args(args)
            .output()
            .expect("run ngcflat")
    };
    let out = plot(true, "p.html");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let t = std::time::Instant::now();
    while !seen.exists() && t.elapsed() < std::time::Duration::from_secs(10) {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let got = std::fs::read_to_string(&seen).expect("the opener was started");
    let want = std::fs::canonicalize(dir.path().join("p.html")).expect("page written");
    assert_eq!(
        std::fs::canonicalize(&got).expect("opened path exists"),
        want
    );
    // Without --open nothing is started.
    std::fs::remove_file(&seen).expect("rm");
    let out = plot(false, "q.html");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(!seen.exists());
}
