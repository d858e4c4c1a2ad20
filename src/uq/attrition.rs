//! The answer in a plant engineer's units (`attrition.csv`): per strength model (and their
//! stacking average), damage model and material, the share of the inventory broken in the first
//! year of operation and the years until 1 % and 10 % of it are broken, each as the median and
//! the 90 % band over the uncertain inputs.
//!
//! P_break(t) of a sample is the expected broken share of an inventory whose particles each see
//! `impacts_per_year · t` impacts (the chain of [`super::setup::Setup`]). For each of a subsample
//! of the Monte Carlo samples (the first [`PER_BLOCK`] of every block, so the blocks' designs
//! stay balanced) P is evaluated on a logarithmic grid of horizons, [`GRID`] per decade from
//! 10⁻² to 10² years, 1 year among them; the years to a share x are where ln P crosses ln x,
//! interpolated linearly in (ln t, ln P) between the grid points that bracket it. A sample whose
//! P stays below x over 100 years counts as "more than 100 years" (+∞ in the quantiles); one
//! whose P is exactly 0 at 100 years never breaks (Vogel–Peukert below its energy threshold),
//! and the share of such samples is reported. P is increasing in t for every damage model, so
//! the first crossing is the only one. Tavares–King's critical ratios x*(N, γ) at the grid's
//! impact counts come from one backward sweep per γ
//! ([`crate::lifetime::damage::CriticalRatioTable::for_impacts`], about 0.6 s for the main
//! study's 41 γ points to 73 000 impacts on two cores). Verified in this file's tests against the
//! closed form of independent trials with one particle type: t_x = −ln(1 − x)/(N_yr H).

use super::forms::Form;
use super::headline::AVERAGED;
use super::propagate::Propagated;
use super::setup::{Mode, Setup};
use crate::error::Result;
use crate::lifetime::attrition::{DECADES, SHARES, grid, years_to};
use crate::lifetime::damage::CriticalRatioTable;
use crate::io::{fcol, scol, table, ReportDir};
use crate::report::captions::{percent, years_text};
use crate::stats::weighted_quantiles;
use rayon::prelude::*;

/// Samples taken from each Monte Carlo block.
pub const PER_BLOCK: usize = 512;

/// One sample's first-year share, years to each of [`SHARES`] and whether it never breaks.
#[derive(Debug, Clone, Copy)]
struct Point {
    first_year: f64,
    years: [f64; 2],
    never: bool,
}

/// Points per (material, damage model) of one strength model: `out[j][k]`; `tk` the
/// Tavares–King tables at the grid's horizons where the study has that model.
fn points(setup: &Setup, prop: &Propagated, tk: Option<&[CriticalRatioTable]>) -> Result<Vec<Vec<Vec<Point>>>> {
    let t = grid();
    let one = t.iter().position(|&y| (y - 1.0).abs() < 1e-12).unwrap_or(0);
    let models = &setup.models;
    let nm = models.len();
    let idx: Vec<(usize, usize)> = (0..prop.blocks.len()).flat_map(|b| (0..prop.blocks[b].n.min(PER_BLOCK)).map(move |i| (b, i))).collect();
    let evaluated: Vec<Vec<f64>> = idx
        .par_iter()
        .map(|&(b, i)| {
            let mut out = vec![0.0; 2 * t.len() * nm];
            setup.evaluate_years(prop.x(b, i), Mode::Joint, &t, models, tk, &mut out)?;
            Ok(out)
        })
        .collect::<Result<_>>()?;
    let mut res = vec![vec![Vec::with_capacity(idx.len()); nm]; 2];
    for out in &evaluated {
        for (j, per_mat) in res.iter_mut().enumerate() {
            for (k, pts) in per_mat.iter_mut().enumerate() {
                let p: Vec<f64> = (0..t.len()).map(|h| out[(j * t.len() + h) * nm + k]).collect();
                pts.push(Point {
                    first_year: p[one],
                    years: [years_to(&t, &p, SHARES[0]), years_to(&t, &p, SHARES[1])],
                    never: p[t.len() - 1] == 0.0,
                });
            }
        }
    }
    Ok(res)
}

/// Quantiles 5, 50, 95 % of weighted values that may be +∞.
fn band(v: Vec<(f64, f64)>) -> [f64; 3] {
    const BIG: f64 = 1e300;
    let q = weighted_quantiles(v.into_iter().map(|(x, w)| (x.min(BIG), w)).collect(), &[0.05, 0.5, 0.95]);
    let back = |x: f64| if x >= BIG * 0.999 { f64::INFINITY } else { x };
    [back(q[0]), back(q[1]), back(q[2])]
}

/// One row of `attrition.csv`.
#[derive(Debug, Clone)]
pub struct Row {
    /// Strength model (or the stacking average).
    pub strength: String,
    /// Damage model code.
    pub model: String,
    /// Damage model in words.
    pub label: String,
    /// Material label.
    pub material: String,
    /// Share broken in the first year: 5, 50, 95 % quantiles.
    pub first_year: [f64; 3],
    /// Years to 1 % broken: 5, 50, 95 % quantiles (+∞: more than 100 years).
    pub to_1pct: [f64; 3],
    /// Years to 10 % broken.
    pub to_10pct: [f64; 3],
    /// Share of the samples in which nothing breaks in 100 years (P exactly 0).
    pub never: f64,
    /// Samples behind the row.
    pub samples: usize,
}

/// The section of `summary.md` with the attrition rows: a table, and in words every row whose
/// model breaks nothing in most samples.
pub fn markdown(rows: &[Row], per_year: &str, candidate: &str) -> String {
    let longest = 10f64.powi(DECADES.1);
    let y = |v: f64| if v.is_infinite() { format!("> {longest:.0}") } else { years_text(v) };
    let b3 = |b: &[f64; 3], f: &dyn Fn(f64) -> String| crate::report::captions::with_band(&f(b[1]), &f(b[0]), &f(b[2]));
    let n = rows.first().map_or(0, |r| r.samples);
    let mut md = format!(
        "\n## In a plant engineer's units\n\nAttrition: the share of the particle inventory broken in the first year of operation ({per_year} impacts per particle), and the years of operation until 1 % and 10 % of it are broken — median and 90 % band over the uncertain inputs, from {n} of the Monte Carlo samples per strength model. These are lifetimes; P({candidate} breaks more) is a comparison. \"> {longest:.0}\": not within {longest:.0} years.\n"
    );
    // Models that break nothing in most samples, said in words first, one sentence per model.
    let mut labels: Vec<&str> = Vec::new();
    for r in rows {
        if !labels.contains(&r.label.as_str()) {
            labels.push(&r.label);
        }
    }
    for l in labels {
        let of: Vec<&Row> = rows.iter().filter(|r| r.label == l).collect();
        let zero: Vec<&&Row> = of.iter().filter(|r| r.never >= 0.5).collect();
        if zero.is_empty() {
            continue;
        }
        let lo = zero.iter().map(|r| r.never).fold(1.0, f64::min);
        let hi = zero.iter().map(|r| r.never).fold(0.0, f64::max);
        let share = if lo == hi { percent(lo) } else { format!("{} to {}", percent(lo), percent(hi)) };
        let whom = if zero.len() == of.len() {
            "for every material under every strength model".to_string()
        } else {
            zero.iter().map(|r| format!("{} ({})", r.material, r.strength)).collect::<Vec<_>>().join(", ")
        };
        md.push_str(&format!(
            "\n**{l} breaks nothing** in {share} of the samples, {whom}: the impacts stay below its energy threshold, so under it the inventory is never broken, however long the plant runs.\n"
        ));
    }
    md.push_str("\n| strength model | damage model | material | broken in year 1 | years to 1 % broken | years to 10 % broken |\n|---|---|---|---|---|---|\n");
    for r in rows {
        md.push_str(&format!("| {} | {} | {} | {} | {} | {} |\n", r.strength, r.label, r.material, b3(&r.first_year, &percent), b3(&r.to_1pct, &y), b3(&r.to_10pct, &y)));
    }
    md
}

/// Writes `attrition.csv` for the strength models `forms` (and their stacking average when
/// there are several) and returns its rows.
pub fn write(dir: &mut ReportDir, forms: &[Form]) -> Result<Vec<Row>> {
    let st = &forms[0].setup;
    // Every strength model shares the damage inputs, hence the tables.
    let tk = st.tk_tables(&grid());
    let per_form: Vec<Vec<Vec<Vec<Point>>>> = forms.iter().map(|f| points(&f.setup, &f.prop, tk.as_deref())).collect::<Result<_>>()?;
    let models = &st.models;
    let mut cols: (Vec<String>, Vec<String>, Vec<String>, Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<f64>, Vec<f64>) = Default::default();
    let mut push = |sm: &str, k: usize, j: usize, pts: Vec<(Point, f64)>| {
        let total: f64 = pts.iter().map(|p| p.1).sum();
        cols.0.push(sm.to_string());
        cols.1.push(models[k].name().to_string());
        cols.2.push(st.materials[j].model.label.clone());
        cols.3.push(band(pts.iter().map(|(p, w)| (p.first_year, *w)).collect()));
        cols.4.push(band(pts.iter().map(|(p, w)| (p.years[0], *w)).collect()));
        cols.5.push(band(pts.iter().map(|(p, w)| (p.years[1], *w)).collect()));
        // (A fold from +0: the sum of no weights is −0.0, which the table would print.)
        cols.6.push(pts.iter().filter(|(p, _)| p.never).fold(0.0, |a, p| a + p.1) / total);
        cols.7.push(pts.len() as f64);
    };
    for (f, pf) in forms.iter().zip(&per_form) {
        for k in 0..models.len() {
            for j in 0..2 {
                push(&f.setup.spec.name(), k, j, pf[j][k].iter().map(|p| (*p, 1.0)).collect());
            }
        }
    }
    if forms.len() > 1 {
        for k in 0..models.len() {
            for j in 0..2 {
                let pooled: Vec<(Point, f64)> = forms
                    .iter()
                    .zip(&per_form)
                    .flat_map(|(f, pf)| {
                        let w = f.weight / pf[j][k].len().max(1) as f64;
                        pf[j][k].iter().map(move |p| (*p, w))
                    })
                    .filter(|x| x.1 > 0.0)
                    .collect();
                push(AVERAGED, k, j, pooled);
            }
        }
    }
    let q = |v: &[[f64; 3]], i: usize| v.iter().map(|b| b[i]).collect::<Vec<f64>>();
    let rows: Vec<Row> = (0..cols.0.len())
        .map(|i| Row {
            strength: cols.0[i].clone(),
            model: cols.1[i].clone(),
            label: models.iter().find(|m| m.name() == cols.1[i]).map_or_else(|| cols.1[i].clone(), |m| m.label().to_string()),
            material: cols.2[i].clone(),
            first_year: cols.3[i],
            to_1pct: cols.4[i],
            to_10pct: cols.5[i],
            never: cols.6[i],
            samples: cols.7[i] as usize,
        })
        .collect();
    dir.write_table(
        "attrition",
        &mut table(vec![
            scol("strength_model", cols.0),
            scol("model", cols.1),
            scol("material", cols.2),
            fcol("first_year_q05", q(&cols.3, 0)),
            fcol("first_year_median", q(&cols.3, 1)),
            fcol("first_year_q95", q(&cols.3, 2)),
            fcol("years_to_1pct_q05", q(&cols.4, 0)),
            fcol("years_to_1pct_median", q(&cols.4, 1)),
            fcol("years_to_1pct_q95", q(&cols.4, 2)),
            fcol("years_to_10pct_q05", q(&cols.5, 0)),
            fcol("years_to_10pct_median", q(&cols.5, 1)),
            fcol("years_to_10pct_q95", q(&cols.5, 2)),
            fcol("never_breaks", cols.6),
            fcol("samples", cols.7),
        ])?,
    )?;
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_keep_infinite_times() {
        let v: Vec<(f64, f64)> = (0..100).map(|i| (if i < 40 { i as f64 } else { f64::INFINITY }, 1.0)).collect();
        let b = band(v);
        assert!(b[0].is_finite() && b[1].is_infinite() && b[2].is_infinite());
    }
}
