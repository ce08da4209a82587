//! Random canned-cycle programs through ngcflat on every target: all of
//! G73 and G81–G89, G98/G99, L repeats, G90/G91, G7 diameter mode, G20
//! inches and plane changes, each lowered program moving the machine as
//! the original does under rs274 (or both refusing it, or the target
//! lacking a code the lowering needs: E1000).
//! `NGCFLAT_CYCLES_CASES`, `NGCFLAT_CYCLES_SEED` choose the programs.

use std::fmt::Write;

use crate::oracle;
use crate::rng::Rng;

const KINDS: [&str; 10] = [
    "G73", "G81", "G82", "G83", "G84", "G85", "G86", "G87", "G88", "G89",
];

/// Program-unit value of `mm` (4 decimals).
fn val(mm: f64, inch: bool) -> String {
    let v = if inch { mm / 25.4 } else { mm };
    let v = (v * 1e4).round() / 1e4;
    let v = if v == 0.0 { 0.0 } else { v };
    format!("{v}")
}

/// The state a random cycle program is written from.
struct Gen {
    rng: Rng,
    inch: bool,
    incremental: bool,
    /// 0 = G17, 1 = G18, 2 = G19.
    plane: usize,
    diameter: bool,
    /// The cycle of the last block (its words are sticky).
    last: Option<&'static str>,
    out: String,
}

impl Gen {
    fn line(&mut self, l: &str) {
        self.out.push_str(l);
        self.out.push('\n');
    }

    /// (first position axis, second, depth axis) letters of the plane.
    fn axes(&self) -> [char; 3] {
        [['X', 'Y', 'Z'], ['Z', 'X', 'Y'], ['Y', 'Z', 'X']][self.plane]
    }

    /// A G90 rapid to a random place with the depth axis above the work.
    fn reposition(&mut self) {
        let [a, b, d] = self.axes();
        let (pa, pb, pd) = (
            self.rng.float(-10.0, 10.0),
            self.rng.float(-10.0, 10.0),
            self.rng.float(2.0, 8.0),
        );
        let i = self.inch;
        let l = format!(
            "G90 G0 {a}{} {b}{} {d}{}",
            val(pa, i),
            val(pb, i),
            val(pd, i)
        );
        self.line(&l);
        if self.incremental {
            self.line("G91");
        }
    }

    fn cycle(&mut self) {
        let kind = *self.rng.pick(&KINDS);
        // G84 taps in G17 only in the reference's lowering; G87 needs the
        // spindle on, which the program keeps.
        let kind = if kind == "G84" && self.plane != 0 {
            "G81"
        } else {
            kind
        };
        let same = self.last == Some(kind);
        let [a, b, d] = self.axes();
        let i = self.inch;
        let mut l = kind.to_string();
        let (lo, hi) = if self.incremental {
            (-3.0, 3.0)
        } else {
            (-10.0, 10.0)
        };
        if self.rng.chance(0.8) {
            let _ = write!(l, " {a}{}", val(self.rng.float(lo, hi), i));
        }
        if self.rng.chance(0.8) {
            let _ = write!(l, " {b}{}", val(self.rng.float(lo, hi), i));
        }
        if !same || self.rng.chance(0.5) {
            // Absolute: R above the depth; incremental: R from the initial
            // level, the depth from R (down).
            let (r, depth) = if self.incremental {
                (self.rng.float(-3.0, 0.5), self.rng.float(-3.0, -0.5))
            } else {
                (self.rng.float(0.5, 3.0), self.rng.float(-3.0, 0.0))
            };
            let _ = write!(l, " {d}{} R{}", val(depth, i), val(r, i));
        }
        match kind {
            "G73" | "G83" if !same || self.rng.chance(0.5) => {
                let _ = write!(l, " Q{}", val(self.rng.float(0.3, 1.5), i));
            }
            "G82" | "G86" | "G88" | "G89" | "G84" if self.rng.chance(0.6) => {
                let _ = write!(
                    l,
                    " P{}",
                    (self.rng.float(0.0, 1.0) * 100.0).round() / 100.0
                );
            }
            "G87" => {
                // The offset point and the back-bore level: I/J/K along the
                // plane's axes, the back-bore one above the depth.
                let ijk = [['I', 'J', 'K'], ['K', 'I', 'J'], ['J', 'K', 'I']][self.plane];
                let _ = write!(
                    l,
                    " {}{} {}{} {}{}",
                    ijk[0],
                    val(self.rng.float(-1.0, 1.0), i),
                    ijk[1],
                    val(self.rng.float(-1.0, 1.0), i),
                    ijk[2],
                    val(self.rng.float(-2.0, 0.0), i)
                );
            }
            _ => {}
        }
        if self.rng.chance(0.3) {
            let _ = write!(l, " L{}", self.rng.int(1, 3));
        }
        if self.rng.chance(0.3) {
            l.insert_str(0, if self.rng.chance(0.5) { "G98 " } else { "G99 " });
        }
        self.line(&l);
        self.last = Some(kind);
    }

    fn step(&mut self) {
        match self.rng.below(14) {
            0..=7 => self.cycle(),
            8 => {
                self.line("G80");
                self.plane = self.rng.below(3);
                let p = ["G17", "G18", "G19"][self.plane];
                self.line(p);
                self.last = None;
                self.reposition();
            }
            9 => {
                self.incremental = !self.incremental;
                self.line(if self.incremental { "G91" } else { "G90" });
            }
            10 => {
                self.diameter = !self.diameter;
                self.line(if self.diameter { "G7" } else { "G8" });
            }
            11 => {
                self.line("G80");
                self.inch = !self.inch;
                self.line(if self.inch { "G20" } else { "G21" });
                self.last = None;
                self.reposition();
            }
            _ => {
                self.line("G80");
                self.last = None;
                self.reposition();
            }
        }
    }
}

/// A random program of canned cycles.
pub fn cycles_program(seed: u64) -> String {
    let mut g = Gen {
        rng: Rng::new(seed),
        inch: seed.is_multiple_of(3),
        incremental: false,
        plane: 0,
        diameter: false,
        last: None,
        out: String::new(),
    };
    let units = if g.inch { "G20" } else { "G21" };
    g.line(&format!("{units} G90 G17 G94 G8 G98 F200 S1000 M3"));
    g.reposition();
    for _ in 0..g.rng.int(4, 12) {
        g.step();
    }
    g.line("G80 G90 G8 G17 G0 X0 Y0 Z10\nM2");
    g.out
}

/// The targets other than `linuxcnc` (which writes cycles as they are).
fn lowering_targets() -> Vec<String> {
    let out = std::process::Command::new(crate::bin())
        .arg("targets")
        .output()
        .expect("ngcflat targets");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_alphanumeric()))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|t| t != "linuxcnc")
        .collect()
}

/// rs274's canon lines of a program (no tool table, an empty INI).
fn rs274(program: &str) -> Result<Vec<String>, String> {
    let dir = crate::tmp();
    let p = dir.path().join("p.ngc");
    std::fs::write(&p, program).map_err(|e| e.to_string())?;
    let ini = dir.path().join("e.ini");
    std::fs::write(&ini, "").map_err(|e| e.to_string())?;
    let out = std::process::Command::new(oracle::RS274)
        .current_dir(dir.path())
        .env("HOME", dir.path())
        .arg("-g")
        .arg("-i")
        .arg(&ini)
        .arg(&p)
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| e.to_string())?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect())
}

/// One program on every lowering target.
fn check(seed: u64, targets: &[String]) -> Result<(), String> {
    let program = cycles_program(seed);
    let original = rs274(&program);
    let dir = crate::tmp();
    crate::put(dir.path(), "p.ngc", &program);
    let mut problems = Vec::new();
    for t in targets {
        let (code, out, err) = crate::run(dir.path(), &["--target", t, "--zero-start", "p.ngc"]);
        let r = match (&original, code) {
            // As LinuxCNC reads it: G4 P in seconds, M0 for a pause code.
            (Ok(a), 0) => rs274(&crate::as_rs274_reads(t, &out))
                .map_err(|e| format!("rs274 rejects the output: {e}"))
                .and_then(|b| crate::motion::same_canon_motion(a, &b, 0.004)),
            // A code the target lacks (G87's spindle orientation M19 on
            // GRBL) is a refusal by design.
            (Ok(_), _) if err.starts_with("error[E1000]") => Ok(()),
            (Ok(_), _) => Err(format!("ngcflat refuses it: {err}")),
            (Err(e), 0) => Err(format!("rs274 refuses it ({e}), ngcflat writes it")),
            (Err(_), _) => Ok(()),
        };
        if let Err(e) = r {
            problems.push(format!("{t}: {e}\n--- output:\n{out}"));
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("\n"))
    }
}

#[test]
fn random_cycle_programs_move_as_rs274_on_every_target() {
    if !oracle::available("random_cycle_programs_move_as_rs274_on_every_target") {
        return;
    }
    let targets = lowering_targets();
    assert!(!targets.is_empty());
    let seeds = oracle::suite_seeds("NGCFLAT_CYCLES", 40);
    let results = oracle::on_threads(seeds, 1, |seed| check(seed, &targets));
    let failures: Vec<String> = results
        .into_iter()
        .filter_map(|(seed, r)| {
            r.err()
                .map(|e| format!("seed {seed}: {e}\n--- program:\n{}", cycles_program(seed)))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} programs move differently:\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}
