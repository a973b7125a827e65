//! Data that cannot support a fit end with exit code 1 and a message saying why and
//! naming what cannot be identified; partially unexcited data drop parameters with the
//! cause in words (issue 13, item 1).

mod scratch;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    scratch::dir("unsupported").join(name)
}

fn fit(log: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(["fit", log.to_str().unwrap(), "--vehicle"])
        .arg(root().join("data/vehicles/quad_x.toml"))
        .arg("--no-diagnose")
        .output()
        .expect("binary runs")
}

const HEADER: &str = "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz";

/// A contract CSV of 2000 rows at 100 Hz (20 s, long enough for the cross-validation
/// blocks) whose row k
/// holds state `state(k)` (u, v, w, p, q, r, Ω₁…Ω₄) and outputs `out(k)` (F, M).
fn write_log(
    name: &str,
    state: impl Fn(usize) -> [f64; 10],
    out: impl Fn(usize) -> [f64; 6],
) -> PathBuf {
    let mut text = format!("{HEADER}\n");
    for k in 0..2000 {
        let _ = write!(text, "{}", k as f64 * 0.01);
        for v in state(k).iter().chain(&out(k)) {
            let _ = write!(text, ",{v}");
        }
        text.push('\n');
    }
    let path = tmp(name);
    std::fs::write(&path, text).unwrap();
    path
}

const HOVER: [f64; 10] = [
    0.4, -0.2, 0.1, 0.01, -0.02, 0.03, 2167.7, 2170.1, 2165.2, 2168.9,
];
const WRENCH: [f64; 6] = [0.01, -0.02, -11.768, 0.001, -0.002, 0.0003];

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_log_of_one_repeated_state_exits_1_saying_there_is_no_excitation() {
    let log = write_log("same.csv", |_| HOVER, |_| WRENCH);
    let o = fit(&log);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(o.stdout.is_empty(), "no tables printed");
    assert!(e.contains("the data cannot support a fit"), "{e}");
    assert!(e.contains("samples hold the same state"), "{e}");
    assert!(e.contains("one distinct state"), "{e}");
    assert!(e.contains("no excitation"), "{e}");
    // Names what cannot be identified.
    assert!(e.contains("C_T0") && e.contains("C_H_mub"), "{e}");
    assert!(!e.contains("inf") && !e.contains("NaN"), "{e}");
}

#[test]
fn constant_inputs_with_varying_outputs_still_hold_one_state() {
    // Zero-variance (NaN-free) inputs; the outputs carry noise, which is no excitation.
    let log = write_log(
        "still.csv",
        |_| HOVER,
        |k| WRENCH.map(|w| w + 1e-3 * ((k as f64) * 1.7).sin()),
    );
    let o = fit(&log);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("one distinct state"), "{e}");
}

#[test]
fn fewer_distinct_states_than_parameters_exit_1() {
    // Three states, repeated: the model's parameters outnumber them.
    let log = write_log(
        "three.csv",
        |k| {
            let mut s = HOVER;
            s[0] += (k % 3) as f64;
            s[6] += 10.0 * (k % 3) as f64;
            s
        },
        |k| WRENCH.map(|w| w * (1.0 + 0.1 * (k % 3) as f64)),
    );
    let o = fit(&log);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("hold only 3 distinct states, fewer than the"),
        "{e}"
    );
    assert!(e.contains("C_T0"), "{e}");
}

/// The shipped quad× sweep with each column of `edits` set to its value in every row.
fn edited_sweep(name: &str, edits: &[(&str, f64)]) -> PathBuf {
    let text = std::fs::read_to_string(root().join("data/quad_x_sweep.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let idx: Vec<(usize, f64)> = edits
        .iter()
        .map(|(c, v)| (header.iter().position(|h| h == c).unwrap(), *v))
        .collect();
    let mut out = header.join(",") + "\n";
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
        for &(i, v) in &idx {
            cells[i] = v.to_string();
        }
        out += &cells.join(",");
        out.push('\n');
    }
    let path = tmp(name);
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_constant_output_exits_1_naming_the_axis_and_its_parameters() {
    // A logged M_z of all zeros (e.g. not logged), on otherwise well-excited data.
    let log = edited_sweep("mz0.csv", &[("mz", 0.0)]);
    let o = fit(&log);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("output Mz is 0 N m in all"), "{e}");
    assert!(e.contains("carries no information"), "{e}");
    assert!(
        e.contains("the parameters only Mz determines cannot be identified"),
        "{e}"
    );
}

#[test]
fn hover_only_data_drop_terms_with_the_cause_in_words() {
    // No in-plane speed: the terms in u, v and V_h are dropped with a warning, the fit
    // goes on (exit 0).
    let log = edited_sweep("hover.csv", &[("u", 0.0), ("v", 0.0)]);
    let o = fit(&log);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let warnings: Vec<&str> = out.lines().filter(|l| l.contains("WARNING")).collect();
    assert!(
        warnings
            .iter()
            .any(|l| l.contains("dropped C_H_mub (u = v = 0 throughout: no in-plane motion)")),
        "{out}"
    );
    // A product is zero when one factor is: the cause names only the variable that was
    // zero in the data (w varies here), never "u = w = 0".
    assert!(
        out.contains("dropped C_H_mub_muw (u*w) (u = 0 throughout: no in-plane motion)"),
        "{out}"
    );
    for w in &warnings {
        // "dropped X (not separable from … X …)" never names a term as its own alias.
        let name = w
            .split("dropped ")
            .nth(1)
            .unwrap()
            .split(" (")
            .next()
            .unwrap();
        let why = w.split_once(" (").unwrap().1;
        assert!(
            !why.contains(&format!("{name},")) && !why.contains(&format!("{name})")),
            "{w}"
        );
    }
    // Every F_x and F_y column is in u, v or V_h: nothing is left to fit there.
    assert!(
        out.contains("OLS Fx  no columns left (all dropped)"),
        "{out}"
    );
    assert!(!out.contains("NaN"), "{out}");
}
