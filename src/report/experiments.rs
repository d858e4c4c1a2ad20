//! Figures of an experiments report (`kind = "experiments"`), drawn from its tables only.
//!
//! | file stem | content | table |
//! |---|---|---|
//! | `experiments_metrics` | each metric against sample size, one line per candidate: probability of choosing the better particle, expected posterior weight of the true damage model, expected 90 % band widths of P_break at the last horizon (both materials summed, a probability), EVSI in the study's currency, each with ±2 Monte Carlo standard errors as bars (not the summed band widths); and, when crush candidates ran it (`naming_draws`), the share of simulated campaigns after which the discrepancy naming loop names the true strength model's effects | `plans.csv` |

use std::path::Path;

use plotters::prelude::SeriesLabelPosition;

use super::canvas::{Encoded, colour};
use super::panel::{Kind, Marker, Panel, Series, figure, padded};
use super::{Rendered, Table, distinct};
use crate::error::Result;

type Drawn = (Encoded, usize);

/// Draws every figure of an experiments report in `dir`.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    super::write_figures(dir, vec![("experiments_metrics", metrics(dir, width_cm)?)])
}

fn metrics(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let t = Table::load(dir, "plans")?;
    let (cand, size) = (t.s("candidate")?, t.f("size")?);
    let names: Vec<String> = t.df.get_column_names().iter().map(|n| n.to_string()).collect();
    let widths: Vec<&String> = names.iter().filter(|n| n.starts_with("width90_p_") && !n.ends_with("_se")).collect();
    let horizon = widths.first().and_then(|n| n.rsplit('_').next()).map(|s| s.trim_end_matches("yr").to_string()).unwrap_or_default();
    let mut band = vec![0.0; cand.len()];
    for w in &widths {
        for (b, v) in band.iter_mut().zip(t.f(w)?) {
            *b += v;
        }
    }
    let evsi = t.f("evsi")?;
    let currency = t.s("currency")?.first().cloned().unwrap_or_default();
    // Each metric with its Monte Carlo standard error, drawn as ±2 se bars (none for the summed
    // band widths: the two materials' widths come from the same datasets and plans.csv gives
    // each width's error alone).
    let mut panels_spec: Vec<(String, Vec<f64>, Option<Vec<f64>>)> = vec![
        ("P(correct choice)".into(), t.f("pcs")?, Some(t.f("pcs_se")?)),
        ("Weight, true damage".into(), t.f("true_damage_model_weight")?, Some(t.f("true_damage_model_weight_se")?)),
        (format!("Σ width P, {horizon} yr"), band, None),
        (format!("EVSI ({currency})"), evsi, Some(t.f("evsi_se")?)),
    ];
    // Only the crush candidates that ran the naming loop have its verdict (NaN elsewhere).
    let naming = t.f("naming_names_truth")?;
    let has_naming = naming.iter().any(|v| v.is_finite());
    if has_naming {
        panels_spec.push(("Naming finds truth".into(), naming, Some(t.f("naming_names_truth_se")?)));
    }
    let candidates = distinct(&cand);
    let x_range = padded(size.iter().cloned(), 0.05, 0.05);
    let n_panels = panels_spec.len();
    let mut panels = Vec::new();
    for (pi, (desc, y, se)) in panels_spec.into_iter().enumerate() {
        let mut series = Vec::new();
        // The error bars first, under the lines and markers; the axis holds them.
        let reach: Vec<f64> = (0..y.len()).map(|i| se.as_ref().map_or(0.0, |s| if s[i].is_finite() { 2.0 * s[i] } else { 0.0 })).collect();
        for (ci, c) in candidates.iter().enumerate() {
            let rows: Vec<usize> = (0..cand.len()).filter(|&i| &cand[i] == c && y[i].is_finite()).collect();
            if rows.is_empty() {
                continue;
            }
            let pts: Vec<(f64, f64)> = rows.iter().map(|&i| (size[i], y[i])).collect();
            for &i in rows.iter().filter(|&&i| reach[i] > 0.0) {
                series.push(Series::line(None, vec![(size[i], y[i] - reach[i]), (size[i], y[i] + reach[i])], colour(ci), 0.6));
            }
            series.push(Series::line(None, pts.clone(), colour(ci), 1.0));
            // Colour and marker together tell up to 18 candidates apart.
            let marker = [Marker::Circle, Marker::Triangle, Marker::Cross][(ci + ci / super::canvas::PALETTE.len()) % 3];
            series.push(Series { label: (pi == 0).then(|| c.clone()), points: pts, colour: colour(ci), kind: Kind::Markers(marker, 2.5) });
        }
        panels.push((
            Panel {
                x_categories: vec![],
                x_desc: if pi + 1 == n_panels { "Sample size (particles or measurements)".into() } else { String::new() },
                y_desc: desc,
                x_range,
                // A probability axis ends at 1; the legend takes the empty lower part below the
                // data of the first panel.
                y_range: if pi == 0 {
                    let lo = y.iter().zip(&reach).map(|(v, r)| v - r).fold(1.0, f64::min);
                    (1.0 - 25.0 * (1.0 - lo).max(0.005), 1.0 + 0.1 * (1.0 - lo).max(0.005))
                } else if has_naming && pi + 1 == n_panels {
                    (0.0, 1.05)
                } else {
                    padded(y.iter().zip(&reach).flat_map(|(v, r)| [v - r, v + r]), 0.1, 0.15)
                },
                y_log: false,
                series,
                legend: (pi == 0).then_some(SeriesLabelPosition::LowerLeft),
            },
            1.0 / n_panels as f64,
        ));
    }
    figure("experiments_metrics", width_cm, 0.45 * n_panels as f64, &panels)
}
