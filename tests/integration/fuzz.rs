//! A short bounded fuzz run on stable Rust (CI has no nightly toolchain and
//! no libFuzzer): the fuzz targets' own harness (`fuzz/harness.rs`) over
//! seeds made from every fixture as `scripts/fuzz-seeds` makes them, then
//! over mutations of them drawn from a fixed random source. A panic fails
//! the test with the input written out. `NGCFLAT_FUZZ_CASES=N` runs N
//! mutations per target (default 1000), `NGCFLAT_FUZZ_SEED=S` another
//! sequence. The long runs use cargo-fuzz (see `fuzz/Cargo.toml`).

use std::path::Path;

use crate::rng::Rng;

#[path = "../../fuzz/harness.rs"]
mod harness;

/// Pieces of G-code spliced into mutated inputs.
const TOKENS: &[&[u8]] = &[
    b"o1 while [#1 LT 3]\n#1=[#1+1]\no1 endwhile\n",
    b"o1 do\no1 while [0]\n",
    b"o1 repeat [3]\nG1 X#1\no1 endrepeat\n",
    b"o1 if [#1]\no1 elseif [1]\no1 else\no1 endif\n",
    b"o100 sub\nG0 X#1\no100 endsub\no100 call [1]\n",
    b"\0sub:f\no<f> sub\nG1 X#1 Y[#2*2]\no<f> endsub\n",
    b"o<f> call [1] [2]\n",
    b"o1 return [1]\n",
    b"#<_v>=[1/0]\n",
    b"#1=[SQRT[-1]]\n",
    b"G2 X1 Y0 R0.5\n",
    b"G3 X0 Y0 I1 J0 P2\n",
    b"G41 D1\nG1 X5\nG40\n",
    b"G81 R1 Z-1\nX1\nG80\n",
    b"G71 Q1 D0.5\n",
    b"G5.2 X1 Y1 P1 L3\nG5.3\n",
    b"M70\nM72\n",
    b"M98 P1 L2\nM99\n",
    b"(debug,#1 #<_v>)\n",
    b"(abort,x)\n",
    b"%\n",
    b"G20\n",
    b"G92 X1\n",
    b"T1 M6 G43\n",
    b"G38.2 Z-1\n#1=#5063\n",
    b"[",
    b"]",
    b"#",
    b"(",
    b"\n",
    b"\0",
    b"\x1b]0;t\x07",
    b"1e308",
    b"-0.0000000001",
    b"99999999999999999999",
];

/// One mutation of `data`: a byte changed, a token put in, a piece cut
/// out or doubled, or a piece of `other` put in.
fn mutate(rng: &mut Rng, data: &mut Vec<u8>, other: &[u8]) {
    let at = |rng: &mut Rng, v: &Vec<u8>| rng.below(v.len() + 1);
    match rng.below(6) {
        0 if !data.is_empty() => {
            let i = rng.below(data.len());
            data[i] = rng.next() as u8;
        }
        1 => {
            let t = TOKENS[rng.below(TOKENS.len())];
            let i = at(rng, data);
            data.splice(i..i, t.iter().copied());
        }
        2 if !data.is_empty() => {
            let i = rng.below(data.len());
            let n = rng.int(1, 64).min(data.len() - i);
            data.drain(i..i + n);
        }
        3 if !data.is_empty() => {
            let i = rng.below(data.len());
            let n = rng.int(1, 256).min(data.len() - i);
            let piece: Vec<u8> = data[i..i + n].to_vec();
            let j = at(rng, data);
            data.splice(j..j, piece);
        }
        4 if !other.is_empty() => {
            let i = rng.below(other.len());
            let n = rng.int(1, 512).min(other.len() - i);
            let j = at(rng, data);
            data.splice(j..j, other[i..i + n].iter().copied());
        }
        _ => {
            // A digit changed: numbers move across their edge cases.
            if let Some(i) = data.iter().position(|b| b.is_ascii_digit()) {
                let k = rng.below(data.len() - i) + i;
                if data[k].is_ascii_digit() {
                    data[k] = b"0123456789"[rng.below(10)];
                }
            }
        }
    }
}

/// The seeds of each target, as `scripts/fuzz-seeds` makes them.
struct Seeds {
    flatten: Vec<Vec<u8>>,
    straight: Vec<Vec<u8>>,
    lines: Vec<Vec<u8>>,
}

fn seeds() -> Seeds {
    let root = crate::root();
    let mut s = Seeds {
        flatten: Vec::new(),
        straight: Vec::new(),
        lines: Vec::new(),
    };
    for ngc in crate::fixtures::all_fixtures() {
        let text = std::fs::read(&ngc).unwrap();
        let rel = ngc.strip_prefix(root.join("fixtures")).unwrap();
        let target = match rel.iter().nth(1).and_then(|t| t.to_str()) {
            Some("grbl") if rel.starts_with("target") => 1,
            Some("grblhal") if rel.starts_with("target") => 2,
            Some("fluidnc") if rel.starts_with("target") => 3,
            _ => 0,
        };
        let mut subs = Vec::new();
        let dir = ngc.parent().unwrap();
        if dir.file_name().is_some_and(|n| n != "subs") {
            subs = sub_files(&dir.join("subs"));
        }
        for flag in [0u8, 1] {
            let mut f = vec![flag, target];
            f.extend_from_slice(&text);
            f.extend_from_slice(&subs);
            s.flatten.push(f);
            let mut t = vec![flag];
            t.extend_from_slice(&text);
            s.straight.push(t);
        }
        s.lines
            .extend(text.split(|&b| b == b'\n').map(<[u8]>::to_vec));
    }
    s.lines.sort();
    s.lines.dedup();
    s
}

/// The files of a `subs` folder as `flatten` input parts.
fn sub_files(dir: &Path) -> Vec<u8> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else {
        return out;
    };
    let mut paths: Vec<_> = rd.map(|e| e.unwrap().path()).collect();
    paths.sort();
    for p in paths {
        if p.extension().is_some_and(|e| e == "ngc") {
            out.extend_from_slice(harness::FILE_MARK);
            out.extend_from_slice(p.file_stem().unwrap().to_string_lossy().as_bytes());
            out.push(b'\n');
            out.extend_from_slice(&std::fs::read(&p).unwrap());
        }
    }
    out
}

/// Runs `run` on `input`; a panic fails the test with the input saved
/// where the long fuzz runs keep theirs, to be made a fixture.
fn run_one(name: &str, run: fn(&[u8]), input: &[u8]) {
    if std::panic::catch_unwind(|| run(input)).is_err() {
        let dir = crate::root().join("fuzz/artifacts");
        let _ = std::fs::create_dir_all(&dir);
        let path = dir.join(format!("{name}-crash-{:016x}", fx(input)));
        let _ = std::fs::write(&path, input);
        panic!(
            "fuzz target {name} failed on the input saved in {}",
            path.display()
        );
    }
}

fn fx(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &x| {
        (h ^ x as u64).wrapping_mul(0x100_0000_01b3)
    })
}

fn env_num(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A target: its name, its harness function and its seeds.
type Target<'a> = (&'a str, fn(&[u8]), &'a Vec<Vec<u8>>);

#[test]
fn fuzz_targets_on_fixtures_and_mutations() {
    let s = seeds();
    assert!(s.flatten.len() > 1000, "{} seeds", s.flatten.len());
    let cases = env_num("NGCFLAT_FUZZ_CASES", 1000) as usize;
    let seed = env_num("NGCFLAT_FUZZ_SEED", 1);
    let targets: [Target; 3] = [
        ("flatten", harness::flatten, &s.flatten),
        ("straight", harness::straight, &s.straight),
        ("parse_line", harness::parse_line, &s.lines),
    ];
    for (k, (name, run, seeds)) in targets.into_iter().enumerate() {
        for input in seeds {
            run_one(name, run, input);
        }
        let mut rng = Rng::new(seed.wrapping_mul(31).wrapping_add(k as u64));
        for _ in 0..cases {
            let mut data = seeds[rng.below(seeds.len())].clone();
            let other = &seeds[rng.below(seeds.len())];
            for _ in 0..rng.int(1, 4) {
                mutate(&mut rng, &mut data, other);
            }
            if name != "parse_line" && !data.is_empty() && rng.chance(0.3) {
                // Other settings, targets and output bounds.
                data[0] = rng.next() as u8;
                if name == "flatten" && data.len() > 1 {
                    data[1] = rng.next() as u8;
                }
            }
            run_one(name, run, &data);
        }
    }
}
