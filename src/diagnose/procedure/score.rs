//! Scoring one candidate against the current model: its trial fit, and the acceptance
//! rules (significant, plausible, predictive on held-out data, paying enough, no large
//! loss; module docs of the procedure).

use super::outcome::{CandidateScore, EffectParameter, Rejection};
use super::state::Search;
use super::trial::{Trial, gains, held_out_lr, joint_p, required_lr, trial};
use crate::diagnose::local::LocalFolds;
use crate::estimate::{self, CrossValidation};
use crate::model::ParamId;

/// Validation gain used to rank accepted candidates of one group: a named hypothesis's
/// gain counts `1 + margin` times ([`crate::diagnose::DiagnoseOptions::unspecific_margin`]),
/// so it is preferred over an unspecific one (a generic term, a freed moment coefficient)
/// unless that explains clearly more.
pub(super) fn preference(s: &CandidateScore, margin: f64) -> f64 {
    if s.role.is_unspecific() {
        s.total_gain
    } else {
        s.total_gain * (1.0 + margin)
    }
}

/// Scores candidate `c` added to the model with columns `kept` (`current`); `local`: the
/// held-out statistics where it acts with `current`'s cross-validation there; it must
/// gain `min_gain` (relative NRMSE) to be accepted, an unspecific hypothesis
/// `1 + unspecific_margin` times as much (it must pay clearly more than a named one
/// would, against nothing as against a named rival: [`preference`]).
pub(super) fn score(
    search: &Search,
    kept: &[usize],
    c: usize,
    current: &Trial,
    local: Option<(&LocalFolds, &CrossValidation)>,
    level: f64,
    min_gain: f64,
) -> (CandidateScore, usize, Option<Trial>) {
    let (stats, options) = (search.stats, search.options);
    let cand = &stats.candidates[c];
    let min_gain = if cand.role.is_unspecific() {
        min_gain * (1.0 + options.unspecific_margin)
    } else {
        min_gain
    };
    let own_params = &stats.candidate_params[c];
    let mut columns = kept.to_vec();
    columns.extend(stats.columns_of(|p| own_params.contains(&p)));
    columns.sort_unstable();
    let axes = cand.axes();
    let mut s = CandidateScore {
        name: cand.name.clone(),
        kind: cand.kind,
        role: cand.role,
        forms_of: cand.forms_of,
        axes: axes.clone(),
        parameters: Vec::new(),
        validation_gain: [0.0; 6],
        total_gain: 0.0,
        held_out_lr: 0.0,
        local_gain: None,
        active_share: local.map_or(1.0, |(lf, _)| lf.share),
        p: 1.0,
        rejected: None,
    };
    let t = match trial(
        stats,
        &columns,
        search.fit_options,
        options.variance_inflation,
    ) {
        Ok(t) => t,
        Err(e) => {
            s.rejected = Some(Rejection::NotEstimable(e.to_string()));
            return (s, c, None);
        }
    };
    // The trial keeps the parameters its columns use, in their order in `extended`.
    let mut used: Vec<ParamId> = t
        .columns
        .iter()
        .map(|&j| stats.extended.columns[j].param)
        .collect();
    used.sort_unstable();
    used.dedup();
    // The same parameters in the trial's structure.
    let own: Vec<ParamId> = own_params
        .iter()
        .map(|p| used.binary_search(p).expect("candidate parameter in trial"))
        .map(ParamId::new)
        .collect();
    s.parameters = own
        .iter()
        .zip(&cand.parameters)
        .map(|(&p, defined)| EffectParameter {
            name: t.structure.param(p).name.clone(),
            estimate: t.fit.mmr.theta[p.index()],
            std: t.std[p.index()],
            unit: t.structure.param(p).unit.clone(),
            p: t.p[p.index()],
            reading: defined.reading,
        })
        .collect();
    s.p = joint_p(&t, &own, options.variance_inflation);
    s.validation_gain = gains(&current.cv, &t.cv);
    s.held_out_lr = held_out_lr(&current.cv, &t.cv);
    s.local_gain = local.and_then(|(lf, before)| {
        let after = estimate::cross_validate(
            &t.structure,
            &lf.folds.select(&t.columns),
            search.fit_options,
        )
        .ok()?;
        Some(gains(before, &after)).filter(|g| g.iter().all(|x| x.is_finite()))
    });
    // The MMR couples the axes through shared parameters, so a candidate can pay on an
    // axis it has no column on (freeing a moment coefficient lets F_z fit itself):
    // gains count on every axis, losses too. A local effect counts where it acts, on
    // its own axes.
    s.total_gain = s.validation_gain.iter().sum();
    let (effect, on_axes): ([f64; 6], Vec<usize>) = match s.local_gain {
        Some(g) => (g, axes.iter().map(|&a| a as usize).collect()),
        None => (s.validation_gain, (0..6).collect()),
    };
    let best_axis = on_axes
        .iter()
        .map(|&a| effect[a])
        .fold(f64::NEG_INFINITY, f64::max);
    let net: f64 = effect.iter().sum();
    let worst = s.validation_gain.iter().fold(0.0_f64, |m, &g| m.min(g));
    let required_lr = required_lr(own.len(), stats.folds, options.variance_inflation, level);
    s.rejected = if s.p >= level {
        Some(Rejection::NotSignificant { p: s.p, level })
    } else if let Some((p, _)) = s
        .parameters
        .iter()
        .zip(&cand.parameters)
        .find(|(p, defined)| !defined.plausible(p.estimate))
    {
        Some(Rejection::Implausible {
            parameter: p.name.clone(),
            value: p.estimate,
            unit: p.unit.clone(),
        })
    } else if s.held_out_lr < required_lr {
        Some(Rejection::NotPredictive {
            statistic: s.held_out_lr,
            required: required_lr,
        })
    } else if best_axis < min_gain {
        Some(Rejection::SmallGain {
            gain: best_axis,
            required: min_gain,
        })
    } else if net < min_gain {
        Some(Rejection::SmallNetGain {
            gain: net,
            required: min_gain,
        })
    } else if worst < -options.max_loss {
        Some(Rejection::Loss { loss: -worst })
    } else {
        None
    };
    (s, c, Some(t))
}
