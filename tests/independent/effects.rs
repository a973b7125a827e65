//! The five hidden effects of the independent simulator, each written from its own
//! physical picture (not from any candidate form of the diagnosis), with the values the
//! harness uses.

/// One hidden effect added to the clean independent model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Hidden {
    /// The downstream (rear, x < 0) rotors fly in the front rotors' wake in forward
    /// flight only: their thrust × (1 − `loss` μ_f), μ_f = max(u, 0)/(Ω R) with u the
    /// body forward airspeed; nothing when flying backwards or hovering.
    RearWake {
        /// Thrust lost per unit forward advance ratio (-).
        loss: f64,
    },
    /// Airframe drag along the airflow with a different area per body axis,
    /// F = −½ ρ |V| (A_x u, A_y v, A_z w), acting at a centre of pressure above the CG
    /// (so it also pitches and rolls the vehicle).
    QuadraticDrag {
        /// Drag areas C_D·A along body x, y, z, m².
        area: [f64; 3],
        /// Centre of pressure relative to the CG, body axes, m.
        centre: [f64; 3],
    },
    /// One rotor (a chipped or wrong propeller) gives a fraction of its thrust and of its
    /// drag torque.
    WeakRotor {
        /// Rotor number as in the vehicle file, from 1.
        rotor: usize,
        /// Thrust fraction (-).
        thrust: f64,
        /// Drag-torque fraction (-).
        torque: f64,
    },
    /// The true CG lies off the point the vehicle file's rotor positions are given from.
    CgOffset {
        /// CG position relative to that point, body axes, m.
        offset: [f64; 3],
    },
    /// Thrust gain near the ground, exponential in the hub's height over the rotor
    /// diameter D: thrust × (1 + `gain` · exp(−z_hub / (`decay` · D))), each rotor at its
    /// own height.
    GroundEffect {
        /// Thrust gain with the hub on the ground (-).
        gain: f64,
        /// Decay height in rotor diameters (-).
        decay: f64,
    },
}

impl Hidden {
    /// The five effects with the harness's values, in table order.
    pub fn all() -> [Hidden; 5] {
        [
            Hidden::RearWake { loss: 1.0 },
            Hidden::QuadraticDrag {
                area: [0.010, 0.012, 0.030],
                centre: [0.0, 0.0, -0.015],
            },
            Hidden::WeakRotor {
                rotor: 2,
                thrust: 0.90,
                torque: 0.93,
            },
            Hidden::CgOffset {
                offset: [-0.008, 0.012, 0.0],
            },
            Hidden::GroundEffect {
                gain: 0.3,
                decay: 0.5,
            },
        ]
    }

    /// The same five kinds at other values, sizes and places than [`Self::all`]'s (a
    /// weaker wake, a drag with other areas acting below the CG, another rotor weak, the
    /// CG off the other way, a weaker ground effect reaching higher): a check that the
    /// diagnosis is not tuned to the harness's values.
    pub fn others() -> [Hidden; 5] {
        [
            Hidden::RearWake { loss: 0.5 },
            Hidden::QuadraticDrag {
                area: [0.020, 0.015, 0.040],
                centre: [0.0, 0.0, 0.010],
            },
            Hidden::WeakRotor {
                rotor: 4,
                thrust: 0.92,
                torque: 0.95,
            },
            Hidden::CgOffset {
                offset: [0.010, 0.006, 0.0],
            },
            Hidden::GroundEffect {
                gain: 0.2,
                decay: 0.8,
            },
        ]
    }

    /// Short label for tables, with the effect's values.
    pub fn label(&self) -> String {
        match self {
            Hidden::RearWake { loss } => format!("rear-rotor wake (u > 0), loss {loss}"),
            Hidden::QuadraticDrag { area, centre } => format!(
                "quadratic airframe drag, areas {:?} m², centre z {} m",
                area, centre[2]
            ),
            Hidden::WeakRotor { rotor, thrust, .. } => {
                format!("weak rotor {rotor}, thrust {thrust}")
            }
            Hidden::CgOffset { offset } => format!("CG offset {offset:?} m"),
            Hidden::GroundEffect { gain, decay } => {
                format!("ground effect (exponential), gain {gain}, decay {decay} D")
            }
        }
    }
}
