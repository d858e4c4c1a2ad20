//! Figures of a temperature report (`kind = "temperature"`), drawn from its tables only.
//!
//! | file stem | content | table |
//! |---|---|---|
//! | `phase_fractions` | every phase's fraction against temperature, amorphous phases dashed (the deliverable's Fig. 2 in °C) | `phases.csv` |

use std::path::Path;

use plotters::prelude::SeriesLabelPosition;

use super::canvas::{Encoded, colour};
use super::panel::{Kind, Panel, Series, figure, padded};
use super::{Rendered, Table, distinct};
use crate::error::Result;

/// Draws every figure of a temperature report in `dir`.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    super::write_figures(dir, vec![("phase_fractions", phase_fractions(dir, width_cm)?)])
}

fn phase_fractions(dir: &Path, width_cm: f64) -> Result<(Encoded, usize)> {
    let t = Table::load(dir, "phases")?;
    let names: Vec<String> = t.df.get_column_names().iter().map(|n| n.to_string()).collect();
    let (column, basis) = if names.iter().any(|n| n == "mass_fraction") { ("mass_fraction", "Mass") } else { ("mole_fraction", "Mole") };
    let (temp, phase, frac, amorphous) = (t.f("temperature_c")?, t.s("phase")?, t.f(column)?, t.s("amorphous")?);
    let mut series = Vec::new();
    for (k, p) in distinct(&phase).iter().enumerate() {
        let rows: Vec<usize> = (0..phase.len()).filter(|&i| &phase[i] == p).collect();
        let points: Vec<(f64, f64)> = rows.iter().map(|&i| (temp[i], frac[i])).collect();
        let glassy = rows.first().is_some_and(|&i| amorphous[i] == "true");
        let label = if glassy { format!("{p} (amorphous)") } else { p.clone() };
        let kind = if glassy { Kind::Dashed(1.6, 4.0, 2.5) } else { Kind::Line(1.2) };
        series.push(Series { label: Some(label), points, colour: colour(k), kind });
    }
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Temperature (°C)".into(),
        y_desc: format!("{basis} fraction of phase (–)"),
        x_range: padded(temp.iter().cloned(), 0.0, 0.0),
        y_range: (0.0, 1.0),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    figure("phase_fractions", width_cm, 0.8, &[(panel, 1.0)])
}
