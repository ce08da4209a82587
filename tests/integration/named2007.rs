//! The 2007 named-parameter proposal's syntax (`--named-params-2007`): a
//! program written in it flattens to the same output as its twin written
//! with today's `#<name>` forms (the twins are fixtures compared with rs274).

use std::path::Path;

use crate::{root, run};

/// (program in the 2007 syntax, its twin under fixtures/ok/named2007)
const TWINS: &[(&str, &str)] = &[("pocket.ngc", "pocket.ngc"), ("scope.ngc", "scope.ngc")];

fn flatten(dir: &Path, name: &str, flag: bool) -> (i32, String, String) {
    let mut args = vec!["--zero-start", "--message-format", "short"];
    if flag {
        args.push("--named-params-2007");
    }
    args.push(name);
    run(dir, &args)
}

#[test]
fn programs_in_the_2007_syntax_flatten_like_their_twins() {
    let old = root().join("tests/integration/named2007");
    let new = root().join("fixtures/ok/named2007");
    for (a, b) in TWINS {
        let (code, out_old, err) = flatten(&old, a, true);
        assert_eq!(code, 0, "{a}: {err}");
        let (code, out_new, err) = flatten(&new, b, false);
        assert_eq!(code, 0, "{b}: {err}");
        // The first line is a comment naming the syntax; the rest is equal.
        let body = |s: &str| s.lines().skip(1).map(str::to_string).collect::<Vec<_>>();
        assert!(out_new.lines().count() > 3, "{b}: {out_new}");
        assert_eq!(body(&out_old), body(&out_new), "{a}");
        // Without the switch the 2007 syntax is not G-code.
        let (code, _, err) = flatten(&old, a, false);
        assert_eq!(code, 1, "{a} without the switch: {err}");
    }
}

#[test]
fn the_syntax_maps_onto_todays_forms() {
    let t = crate::tmp();
    let cases: &[(&str, &str)] = &[
        // #[name]: blanks removed, lower-cased; a function keeps its meaning.
        (
            "#[Feed Rate] = 3\nG1 F100 X#[feedrate]\nM2\n",
            "G1 F100 X3\n",
        ),
        ("#9 = 2\nG1 F100 X#[SQRT[81]]\nM2\n", "G1 F100 X2\n"),
        // #name$ is global: seen in a subroutine; #$name$ is local.
        (
            "#g$ = 4\n#$l$ = 1\nos$ sub\n#$l$ = 7\nG1 X#g$ Y#$l$\nos$ endsub\nG1 F100\nos$ call\nG1 X#$l$\nM2\n",
            "G1 F100\nG1 X4 Y7\nG1 X1\n",
        ),
        // o$name$ labels are local to their subroutine, as o<name>.
        (
            "o$loop$ repeat [2]\nG1 F100 X1\no$loop$ endrepeat\nM2\n",
            "G1 F100 X1\nG1 F100 X1\n",
        ),
    ];
    for (i, (prog, want)) in cases.iter().enumerate() {
        let name = format!("p{i}.ngc");
        crate::put(t.path(), &name, prog);
        let (code, out, err) = flatten(t.path(), &name, true);
        assert_eq!(code, 0, "{prog}: {err}");
        assert_eq!(out, format!("{want}M2\n"), "{prog}");
    }
}

#[test]
fn error_positions_point_into_the_line_as_written() {
    let t = crate::tmp();
    let line = "G1 F100 X#Some Name$ Y#[other] Z[1/0]";
    crate::put(
        t.path(),
        "e.ngc",
        &format!("#somename$ = 1\n#[other] = 2\n{line}\nM2\n"),
    );
    let (code, _, err) = flatten(t.path(), "e.ngc", true);
    assert_eq!(code, 1, "{err}");
    let col = line.find("[1/0]").unwrap() + 1;
    assert!(err.contains(&format!("e.ngc:3:{col}:")), "{err}");
    // An undefined name is reported as the #<name> it maps onto, at its place.
    crate::put(t.path(), "u.ngc", "G1 F100 X#[Missing]\nM2\n");
    let (code, _, err) = flatten(t.path(), "u.ngc", true);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("u.ngc:1:10:") && err.contains("#<missing>"),
        "{err}"
    );
}
