//! Malformed and physically invalid vehicle files: each gets its own specific error that
//! names the file and the field or rotor, never a panic. Layouts that break only the
//! symmetry parts of Assumption 2 are accepted with notes.

use mrsysid::vehicle::{Vehicle, VehicleSource};

const HEADER: &str = r#"
name = "t"
mass = 1.2
inertia = [[0.011, 0, 0], [0, 0.012, 0], [0, 0, 0.021]]
rotor_radius = 0.0635
hub_height = 0.02
rotor_inertia = 3.0e-5
"#;

fn rotors(table: &[(f64, f64, i64)]) -> String {
    table
        .iter()
        .map(|(x, y, s)| format!("[[rotors]]\nx = {x}\ny = {y}\nspin = {s}\n"))
        .collect()
}

const QUAD_X: [(f64, f64, i64); 4] = [
    (0.159, 0.159, 1),
    (-0.159, 0.159, -1),
    (-0.159, -0.159, 1),
    (0.159, -0.159, -1),
];

fn error_of(text: &str) -> String {
    match Vehicle::from_toml_str(text, VehicleSource::File("bad.toml".into())) {
        Ok(v) => panic!("accepted an invalid vehicle: {v:?}"),
        Err(e) => e.to_string(),
    }
}

fn assert_error(text: &str, expected: &[&str]) {
    let msg = error_of(text);
    assert!(
        msg.starts_with("bad.toml: "),
        "error does not name the file: {msg}"
    );
    for part in expected {
        assert!(msg.contains(part), "error `{msg}` lacks `{part}`");
    }
}

#[test]
fn valid_file_is_accepted() {
    let v = Vehicle::from_toml_str(&format!("{HEADER}{}", rotors(&QUAD_X)), VehicleSource::Code)
        .unwrap();
    assert_eq!(v.rotor_count(), 4);
    assert!((v.arm_length() - 0.159 * 2f64.sqrt()).abs() < 1e-12);
}

#[test]
fn missing_field() {
    let text = format!("{}{}", HEADER.replace("mass = 1.2\n", ""), rotors(&QUAD_X));
    assert_error(&text, &["missing field `mass`"]);
}

#[test]
fn toml_syntax_error() {
    assert_error(
        "name = \"t\"\nmass = = 1\n",
        &["TOML error at line 2 (`mass = = 1`)"],
    );
}

#[test]
fn wrong_type() {
    let text = format!(
        "{}{}",
        HEADER.replace("mass = 1.2", "mass = \"heavy\""),
        rotors(&QUAD_X)
    );
    assert_error(
        &text,
        &["TOML error at line 3 (`mass = \"heavy\"`): invalid type"],
    );
}

#[test]
fn unknown_field_is_a_typo_not_ignored() {
    let text = format!("{HEADER}rotor_raduis = 0.1\n{}", rotors(&QUAD_X));
    assert_error(&text, &["unknown field `rotor_raduis`"]);
}

#[test]
fn negative_mass() {
    let text = format!(
        "{}{}",
        HEADER.replace("mass = 1.2", "mass = -1.2"),
        rotors(&QUAD_X)
    );
    assert_error(
        &text,
        &["field `mass` = -1.2", "must be a finite number > 0"],
    );
}

#[test]
fn zero_rotor_radius() {
    let text = format!(
        "{}{}",
        HEADER.replace("rotor_radius = 0.0635", "rotor_radius = 0.0"),
        rotors(&QUAD_X)
    );
    assert_error(&text, &["field `rotor_radius` = 0"]);
}

#[test]
fn nan_air_density() {
    let text = format!("{HEADER}air_density = nan\n{}", rotors(&QUAD_X));
    assert_error(&text, &["field `air_density` = NaN"]);
}

#[test]
fn negative_rotor_inertia() {
    let text = format!(
        "{}{}",
        HEADER.replace("rotor_inertia = 3.0e-5", "rotor_inertia = -3.0e-5"),
        rotors(&QUAD_X)
    );
    assert_error(&text, &["field `rotor_inertia`", ">= 0"]);
}

#[test]
fn inertia_not_positive_definite() {
    let text = format!(
        "{}{}",
        HEADER.replace(
            "[[0.011, 0, 0], [0, 0.012, 0], [0, 0, 0.021]]",
            "[[0.011, 0.02, 0], [0.02, 0.012, 0], [0, 0, 0.021]]"
        ),
        rotors(&QUAD_X)
    );
    assert_error(&text, &["field `inertia`: not positive definite"]);
}

#[test]
fn inertia_not_symmetric() {
    let text = format!(
        "{}{}",
        HEADER.replace(
            "[[0.011, 0, 0], [0, 0.012, 0], [0, 0, 0.021]]",
            "[[0.011, 0.001, 0], [0, 0.012, 0], [0, 0, 0.021]]"
        ),
        rotors(&QUAD_X)
    );
    assert_error(
        &text,
        &["field `inertia`: not symmetric: I[0][1] = 0.001 but I[1][0] = 0"],
    );
}

#[test]
fn odd_rotor_count() {
    let three = [(0.2, 0.0, 1), (-0.1, 0.173, -1), (-0.1, -0.173, 1)];
    assert_error(
        &format!("{HEADER}{}", rotors(&three)),
        &["Assumption 2 fails (even rotor count N >= 4)", "3 rotors"],
    );
}

#[test]
fn duplicate_rotor_position() {
    let dup = [
        (0.159, 0.159, 1),
        (-0.159, 0.159, -1),
        (-0.159, -0.159, 1),
        (0.159, 0.159, -1),
    ];
    assert_error(
        &format!("{HEADER}{}", rotors(&dup)),
        &["rotor 4", "same position as rotor 1 (duplicate rotor)"],
    );
}

#[test]
fn spins_following_the_side_couple_yaw_to_roll() {
    // Right rotors +1, left rotors −1: balanced, but σ_i = y_i/|y_i| makes the rudder row
    // of the mixing matrix a multiple of the aileron row.
    let same = [
        (0.159, 0.159, 1),
        (-0.159, 0.159, 1),
        (-0.159, -0.159, -1),
        (0.159, -0.159, -1),
    ];
    assert_error(
        &format!("{HEADER}{}", rotors(&same)),
        &[
            "Assumption 2 fails (independent thrust, roll, pitch and yaw)",
            "the mixing matrix (Eq. 20) has rank 3",
            "y_i/l",
            "spin_i = 0 for every rotor",
        ],
    );
}

#[test]
fn unbalanced_spins() {
    let three_cw = [
        (0.159, 0.159, 1),
        (-0.159, 0.159, -1),
        (-0.159, -0.159, 1),
        (0.159, -0.159, 1),
    ];
    assert_error(
        &format!("{HEADER}{}", rotors(&three_cw)),
        &[
            "Assumption 2 fails (balanced spins)",
            "3 rotors spin +1 and 1 spin -1",
        ],
    );
}

/// Accepted as a general planar layout; the breach is a note naming the condition and
/// the rotor, and the class is `general planar`.
fn assert_note(text: &str, expected: &[&str]) {
    let v = Vehicle::from_toml_str(text, VehicleSource::File("ok.toml".into()))
        .unwrap_or_else(|e| panic!("refused a general planar layout: {e}"));
    assert_eq!(v.class().to_string(), "general planar");
    assert!(!v.satisfies_assumption2());
    let notes = v.notes();
    let all = notes.join("\n");
    for part in expected {
        assert!(all.contains(part), "notes `{all}` lack `{part}`");
    }
    assert!(
        notes.last().unwrap().contains("general planar layout"),
        "{all}"
    );
}

#[test]
fn unequal_arms_is_a_note() {
    let long = [
        (0.159, 0.159, 1),
        (-0.159, 0.159, -1),
        (-0.2, -0.2, 1),
        (0.159, -0.159, -1),
    ];
    assert_note(
        &format!("{HEADER}{}", rotors(&long)),
        &[
            "Assumption 2 does not hold (equal arms)",
            "rotor 3 has arm",
            "(symmetric about the body x axis)",
        ],
    );
}

#[test]
fn unequal_interior_angles_is_a_note() {
    // Equal arms, but rotors 1/4 at ±30° and 2/3 at ±150°: gaps of 60° and 120°.
    let (c, s) = (0.225 * 0.866_025_403_784_438_6, 0.225 * 0.5);
    let bent = [(c, s, 1), (-c, s, -1), (-c, -s, 1), (c, -s, -1)];
    assert_note(
        &format!("{HEADER}{}", rotors(&bent)),
        &[
            "Assumption 2 does not hold (equal interior angles)",
            "deg apart, expected 90.0000 deg",
        ],
    );
}

#[test]
fn asymmetric_layout_is_a_note() {
    // Equal arms and 90° gaps, but rotated by 20°: not symmetric about the body axes.
    let a = 20f64.to_radians();
    let table: Vec<(f64, f64, i64)> = (0..4)
        .map(|k| {
            let phi = a + k as f64 * std::f64::consts::FRAC_PI_2;
            (
                0.225 * phi.cos(),
                0.225 * phi.sin(),
                if k % 2 == 0 { 1 } else { -1 },
            )
        })
        .collect();
    assert_note(
        &format!("{HEADER}{}", rotors(&table)),
        &[
            "Assumption 2 does not hold (symmetric about the body x axis)",
            "rotor 1",
        ],
    );
}

#[test]
fn bad_spin_value() {
    let bad = [
        (0.159, 0.159, 2),
        (-0.159, 0.159, -1),
        (-0.159, -0.159, 1),
        (0.159, -0.159, -1),
    ];
    assert_error(
        &format!("{HEADER}{}", rotors(&bad)),
        &["rotor 1", "spin = 2 must be +1 or -1"],
    );
}

#[test]
fn canted_rotor() {
    let text = format!("{HEADER}{}", rotors(&QUAD_X)).replacen(
        "spin = 1\n",
        "spin = 1\ncant_deg = 10\n",
        1,
    );
    assert_error(
        &text,
        &[
            "Assumption 2 fails (uncanted rotors)",
            "rotor 1 is canted by 10 deg",
        ],
    );
}

#[test]
fn rotor_off_the_rotor_plane() {
    let text =
        format!("{HEADER}{}", rotors(&QUAD_X)).replacen("spin = 1\n", "spin = 1\nz = 0.05\n", 1);
    assert_error(
        &text,
        &[
            "Assumption 2 fails (coplanar rotors at one height)",
            "rotor 1 has z = 0.05 m",
        ],
    );
}

#[test]
fn preset_and_table_both_given() {
    let text = format!(
        "{HEADER}preset = \"quad_x\"\narm_length = 0.2\n{}",
        rotors(&QUAD_X)
    );
    assert_error(
        &text,
        &["give either `preset` or a [[rotors]] table, not both"],
    );
}

#[test]
fn no_rotors() {
    assert_error(HEADER, &["no rotors"]);
}

#[test]
fn preset_without_arm_length() {
    assert_error(
        &format!("{HEADER}preset = \"hexa_x\"\n"),
        &["`preset` needs `arm_length` (m)"],
    );
}

#[test]
fn unknown_preset() {
    assert_error(
        &format!("{HEADER}preset = \"tricopter\"\narm_length = 0.2\n"),
        &["unknown variant `tricopter`"],
    );
}

#[test]
fn missing_file_names_the_path() {
    let e = Vehicle::from_toml_file(std::path::Path::new("/nonexistent/v.toml")).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/v.toml: cannot read file"),
        "{e}"
    );
}

#[test]
fn shipped_vehicle_files_load() {
    for f in ["quad_x", "quad_plus", "hexa_x"] {
        let path = format!("{}/data/vehicles/{f}.toml", env!("CARGO_MANIFEST_DIR"));
        Vehicle::from_toml_file(std::path::Path::new(&path)).unwrap();
    }
}

#[test]
fn too_many_rotors() {
    let table: Vec<(f64, f64, i64)> = (0..66)
        .map(|k| {
            let phi = 2.0 * std::f64::consts::PI * k as f64 / 66.0;
            (
                0.5 * phi.cos(),
                0.5 * phi.sin(),
                if k % 2 == 0 { 1 } else { -1 },
            )
        })
        .collect();
    assert_error(
        &format!("{HEADER}{}", rotors(&table)),
        &["66 rotors: at most 64 are supported"],
    );
}

/// Lengths in mm where m are expected: the rotor positions (arms 225 m) or the rotor
/// radius (63.5 m) a thousand times too large, named against each other; the largest
/// ratio accepted is 50 either way (real multirotors: 1 to 5).
#[test]
fn a_length_in_millimetres_is_named() {
    let mm: Vec<(f64, f64, i64)> = QUAD_X
        .iter()
        .map(|&(x, y, s)| (x * 1e3, y * 1e3, s))
        .collect();
    assert_error(
        &format!("{HEADER}{}", rotors(&mm)),
        &[
            "arm length 224.860 m (from the rotor positions) is 3541 times the rotor_radius 0.0635 m",
            "in mm?",
        ],
    );
    let radius = HEADER.replace("rotor_radius = 0.0635", "rotor_radius = 63.5");
    assert_error(
        &format!("{radius}{}", rotors(&QUAD_X)),
        &[
            "rotor_radius 63.5 m is 282 times the arm length 0.225 m",
            "in mm?",
        ],
    );
    let ok = HEADER.replace("rotor_radius = 0.0635", "rotor_radius = 0.0045");
    Vehicle::from_toml_str(
        &format!("{ok}{}", rotors(&QUAD_X)),
        VehicleSource::File("ok.toml".into()),
    )
    .expect("a ratio of 50 is accepted");
}

/// The inertia may be given as its diagonal (principal body axes); any other shape is
/// refused naming both forms, at its line.
#[test]
fn inertia_as_a_diagonal_is_read_and_other_shapes_say_both_forms() {
    let diagonal = HEADER.replace(
        "inertia = [[0.011, 0, 0], [0, 0.012, 0], [0, 0, 0.021]]",
        "inertia = [0.011, 0.012, 0.021]",
    );
    let read = |header: &str| {
        Vehicle::from_toml_str(
            &format!("{header}{}", rotors(&QUAD_X)),
            VehicleSource::File("v.toml".into()),
        )
    };
    assert_eq!(
        read(&diagonal).unwrap().props.inertia,
        read(HEADER).unwrap().props.inertia
    );
    let two = HEADER.replace(
        "inertia = [[0.011, 0, 0], [0, 0.012, 0], [0, 0, 0.021]]",
        "inertia = [0.011, 0.012]",
    );
    assert_error(
        &format!("{two}{}", rotors(&QUAD_X)),
        &[
            "line 4",
            "expected a 3x3 matrix [[Ixx, Ixy, Ixz]",
            "or its diagonal [Ixx, Iyy, Izz]",
        ],
    );
}
