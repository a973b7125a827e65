//! The `simulate` shell: exit status, messages, and no partial output on failure.

mod scratch;
use std::process::Command;

fn run(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_input_fails_cleanly_and_writes_nothing() {
    let dir = scratch::dir("sim-cli");
    let out = dir.join("out.csv");
    let out_s = out.to_str().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (
            &[
                "--preset",
                "quad_x",
                "--mode",
                "sweep",
                "--effect",
                "weak_rotor=9,0.5",
            ],
            "rotor 9 does not exist",
        ),
        (
            &[
                "--preset", "quad_x", "--mode", "sweep", "--effect", "wind=1,2",
            ],
            "takes",
        ),
        (
            &["--vehicle", "no/such.toml", "--mode", "sweep"],
            "no/such.toml",
        ),
        (
            &[
                "--preset",
                "quad_x",
                "--mode",
                "sweep",
                "--effect",
                "inflow_lag=0.01",
            ],
            "needs `--mode flight`",
        ),
        (
            &[
                "--preset",
                "quad_x",
                "--mode",
                "flight",
                "--duration",
                "1",
                "--effect",
                "smoothed_loads=50",
            ],
            "below half the sample rate",
        ),
        (
            &[
                "--preset",
                "quad_x",
                "--mode",
                "flight",
                "--log-rate",
                "300",
            ],
            "whole number",
        ),
    ];
    for (args, needle) in cases {
        let mut all = vec!["simulate", "--out", out_s];
        all.extend_from_slice(args);
        let (ok, err) = run(&all);
        assert!(!ok, "{args:?} succeeded");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} left a file");
    }
    let (ok, err) = run(&[
        "simulate", "--preset", "hexa_x", "--mode", "sweep", "--points", "5", "--out", out_s,
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text.lines().count(), 6);
    assert!(text.starts_with("t,u,v,w,p,q,r,omega_1,"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A bad `--rotor` file is refused with the file, the line and the reason.
#[test]
fn bad_rotor_file_names_file_line_and_field() {
    let dir = scratch::dir("sim-rotor");
    let rotor = dir.join("rotor.toml");
    let out = dir.join("out.csv");
    for (text, needles) in [
        (
            "blades = 2\nchord = \"x\"\n",
            vec!["rotor.toml", "line 2", "expected f64"],
        ),
        ("\nbogus = 1\n", vec!["line 2", "unknown field `bogus`"]),
        ("stall_angle = 1.2\n", vec!["stall_angle", "below pi/4"]),
    ] {
        std::fs::write(&rotor, text).unwrap();
        let (ok, err) = run(&[
            "simulate",
            "--preset",
            "quad_x",
            "--mode",
            "sweep",
            "--rotor",
            rotor.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(!ok);
        for n in needles {
            assert!(err.contains(n), "{text:?}: {err}");
        }
        assert!(!out.exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
