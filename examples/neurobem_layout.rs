//! Reads NeuroBEM CSV logs through `examples/neurobem.toml` and prints what the data say
//! about the motor layout (positions, spins, arm length) and data quality.
//!
//! `cargo run --release --example neurobem_layout -- data/vehicles/neurobem.toml FILE...`

use std::path::Path;

use mrsysid::io::{Mapping, ReadOptions, open_log};
use mrsysid::vehicle::Vehicle;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((vehicle_path, files)) = args.split_first() else {
        return Err("usage: neurobem_layout VEHICLE.toml FILE.csv...".into());
    };
    let vehicle = Vehicle::from_toml_file(Path::new(vehicle_path))?;
    let mapping = Mapping::from_toml_file(Path::new("examples/neurobem.toml"))?;
    for file in files {
        let mut reader = open_log(
            Path::new(file),
            &vehicle,
            Some(&mapping),
            &ReadOptions::default(),
        )?;
        let samples: usize = reader
            .by_ref()
            .map(|c| c.map(|c| c.len()))
            .sum::<Result<usize, _>>()?;
        let s = reader.summary();
        println!(
            "{file}: {samples} samples, {} segments, spikes {:?}, dropped {:?}",
            s.segments, s.spikes, s.dropped
        );
        println!("  unit warnings: {:?}", s.unit_warnings);
        if let Some(l) = &s.layout {
            println!(
                "  layout: k = {:.4e} N s^2, arm = {:.4} m, J_z = {:?}, R2 [Mx My Mz Fz] = {:.3?}",
                l.thrust_coefficient, l.arm_length, l.rotor_inertia, l.r_squared
            );
            for (i, (p, s)) in l.positions.iter().zip(&l.spins).enumerate() {
                println!(
                    "    rotor {}: x = {:+.4} m, y = {:+.4} m, spin {:+}",
                    i + 1,
                    p[0],
                    p[1],
                    s
                );
            }
        }
    }
    Ok(())
}
