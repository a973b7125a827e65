//! One sentence per effect added: what the candidate's own statement says with its
//! estimates ("rotor 3 weaker by 9.8 %", else its name), with what the data cannot
//! separate it from and the look-alikes that explain about as much.

use super::outcome::CandidateScore;
use crate::diagnose::candidate::Candidate;

/// One sentence for `cand` added as scored in `s`, with the candidates of its family the
/// data cannot separate from it and the look-alikes of other kinds that explain about as
/// much.
pub(super) fn finding(
    cand: &Candidate,
    s: &CandidateScore,
    not_separable: &[String],
    look_alikes: &[String],
) -> String {
    let mut said = describe(cand, s);
    if !not_separable.is_empty() {
        said = format!(
            "{said} or {} (not separable with these data)",
            not_separable.join(" or ")
        );
    }
    if !look_alikes.is_empty() {
        said = format!("{said}; explains about as much: {}", look_alikes.join(", "));
    }
    said
}

/// What a finding says of `cand` with the estimates of its score `s`
/// ([`Candidate::describe`]).
pub(super) fn describe(cand: &Candidate, s: &CandidateScore) -> String {
    let estimates: Vec<f64> = s.parameters.iter().map(|p| p.estimate).collect();
    cand.describe(&estimates)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::candidate::{EffectKind, Role, Statement};
    use crate::diagnose::procedure::EffectParameter;
    use crate::sample::Axis;

    /// Rotor `rotor`'s asymmetry candidate and its score with thrust fraction `scale`.
    fn weak_rotor(rotor: usize, scale: f64) -> (Candidate, CandidateScore) {
        let name = format!("weak rotor {rotor}");
        let cand = Candidate::new(
            EffectKind::RotorAsymmetry,
            Role::Mechanism,
            name.clone(),
            "",
            Vec::new(),
        )
        .stated_as(Statement::Change {
            parameter: 0,
            less: format!("rotor {rotor} weaker"),
            more: format!("rotor {rotor} stronger"),
        });
        let score = CandidateScore {
            name,
            kind: cand.kind,
            role: cand.role,
            forms_of: None,
            axes: vec![Axis::Fz],
            parameters: vec![EffectParameter {
                name: format!("thrust_scale_{rotor}"),
                estimate: scale,
                std: 0.001,
                unit: "-".into(),
                p: 0.0,
                reading: Default::default(),
            }],
            validation_gain: [0.0; 6],
            total_gain: 0.0,
            held_out_lr: 500.0,
            local_gain: None,
            active_share: 1.0,
            p: 0.0,
            rejected: None,
        };
        (cand, score)
    }

    #[test]
    fn a_rotor_asymmetry_is_reported_with_its_direction_and_its_equivalent() {
        let (weak3, s3) = weak_rotor(3, -0.098);
        let (strong1, s1) = weak_rotor(1, 0.102);
        assert_eq!(describe(&strong1, &s1), "rotor 1 stronger by 10.2 %");
        assert_eq!(finding(&weak3, &s3, &[], &[]), "rotor 3 weaker by 9.8 %");
        assert_eq!(
            finding(&weak3, &s3, &[describe(&strong1, &s1)], &[]),
            "rotor 3 weaker by 9.8 % or rotor 1 stronger by 10.2 % (not separable with these data)"
        );
        assert_eq!(
            finding(&weak3, &s3, &[], &["CG offset".into()]),
            "rotor 3 weaker by 9.8 %; explains about as much: CG offset"
        );
    }
}
