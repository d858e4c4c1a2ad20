//! Observations: what each row of a strength sample says about its value, not only the value.
//!
//! A specimen's row is one of
//!
//! | kind | the row says | likelihood contribution |
//! |---|---|---|
//! | exact | broke at x | ln f(x) |
//! | right-censored | did not break by x (the rig's limit, a run-out) | ln S(x) = ln[1 − F(x)] |
//! | left-censored | broke at or below x (during set-up, below the preload) | ln F(x) |
//! | interval | broke between x and x_u (a strength class of a grouped table) | ln[F(x_u) − F(x)] |
//!
//! (Lawless 2003, *Statistical Models and Methods for Lifetime Data*, §2.2; the same four kinds
//! as `reliability`'s and surpyval's `x, c, n` — there with the count n per row.) A row that
//! counts k specimens (a `count` column) is k specimens: the readers expand it, so the bootstrap,
//! the cross-validation folds, the residuals and the plots see specimens, and a grouped table
//! is fitted exactly as the table of its specimens.
//!
//! **Redrawing as the campaign censored** ([`Obs::censor`]). A parametric bootstrap of a
//! censored sample must censor each redraw as the campaign did (type I censoring at the
//! recorded limits), or its spread is that of a complete sample. Each row carries its limits
//! ([`Scheme`]): a right-censored row its own limit; an exact row the campaign's rig limit (none
//! where the file has no unbroken specimen) — or, where the recorded limits differ (random
//! censoring: each test stopped at its own load), a limit drawn for each redraw from the
//! limits' distribution estimated by the reverse Kaplan–Meier estimate (the limits are the
//! events, the breaks censor them; Efron 1981), given that it lay above the row's own break; a
//! left-censored row its own limit; an interval row the class edges of its file, so a redraw
//! falls into the class that holds it (below the lowest edge: left-censored there; above the
//! highest: right-censored there). The limits are in the row's own units: a crush file's rig
//! limit in force becomes each particle's σ̄ at that force.
//!
//! Verified by the unit tests below and those of `strength::regress` (the censored likelihood's
//! derivatives, the censored MLE against `reliability`).

use std::sync::Arc;

/// What a row says about its value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Censor {
    /// Broke at the value.
    Exact,
    /// Did not break by the value (right-censored).
    Right,
    /// Broke at or below the value (left-censored).
    Left,
    /// Broke between the value and the row's upper value.
    Interval,
}

impl Censor {
    /// Words for a table (`exact`, `right`, `left`, `interval`).
    pub fn name(self) -> &'static str {
        match self {
            Censor::Exact => "exact",
            Censor::Right => "right",
            Censor::Left => "left",
            Censor::Interval => "interval",
        }
    }

    /// The kind [`Censor::name`] writes, read back from a table (None for anything else).
    pub fn parse(s: &str) -> Option<Censor> {
        [Censor::Exact, Censor::Right, Censor::Left, Censor::Interval].into_iter().find(|k| k.name() == s)
    }

    /// Words for a plot's legend: what a point of this kind is (`not broken`, `broke below`,
    /// `class ends`, `broke`).
    pub fn plotted(self) -> &'static str {
        match self {
            Censor::Exact => "broke",
            Censor::Right => "not broken",
            Censor::Left => "broke below",
            Censor::Interval => "class ends",
        }
    }
}

/// How a redraw of each row is censored (module docs): limits in the row's own units.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Scheme {
    /// Right limit per row (∞: none).
    pub right: Vec<f64>,
    /// Left limit per row (0: none).
    pub left: Vec<f64>,
    /// Class edges per row, ascending (empty for a row that is not an interval).
    pub edges: Vec<Vec<f64>>,
    /// Where the recorded right limits differ: per exact row, the limits a redraw's limit is
    /// drawn from with their probabilities (∞ for no limit), in the row's units; empty for a
    /// row whose limit is `right` (every row, when the file has one limit).
    pub right_draws: Vec<Vec<(f64, f64)>>,
}

/// What the rows of a sample say beyond their values (absent: every row is exact).
#[derive(Debug, Clone, PartialEq)]
pub struct Censoring {
    /// Each row's kind.
    pub kind: Vec<Censor>,
    /// The upper value of an interval row (NaN for the others).
    pub upper: Vec<f64>,
    /// How a redraw of each row is censored.
    pub scheme: Arc<Scheme>,
}

/// The observations of a sample, owned: values and what the rows say of them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Observations {
    /// The value of each row: the strength at break (exact), the limit (censored), the lower
    /// value (interval).
    pub x: Vec<f64>,
    /// What the rows say (None: every row is exact).
    pub censoring: Option<Censoring>,
}

/// A borrowed view of observations, what the fits take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Obs<'a> {
    /// Values (see [`Observations::x`]).
    pub x: &'a [f64],
    /// What the rows say (None: every row is exact).
    pub censoring: Option<&'a Censoring>,
}

/// The number of rows of each kind: exact, right-censored, left-censored, interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Tally {
    /// Broke at their value.
    pub exact: usize,
    /// Did not break by their value.
    pub right: usize,
    /// Broke at or below their value.
    pub left: usize,
    /// Broke within a class.
    pub interval: usize,
}

impl Tally {
    /// Every row.
    pub fn total(&self) -> usize {
        self.exact + self.right + self.left + self.interval
    }

    /// Whether every row is exact.
    pub fn complete(&self) -> bool {
        self.total() == self.exact
    }

    /// In words: `60 specimens: 50 broke at a recorded value, 10 did not break by their limit`.
    pub fn describe(&self, what: &str) -> String {
        let mut parts = Vec::new();
        let their = |k: usize| if k == 1 { "its" } else { "their" };
        if self.exact > 0 {
            parts.push(format!("{} broke at a recorded value", self.exact));
        }
        if self.right > 0 {
            parts.push(format!("{} did not break by {} limit (right-censored)", self.right, their(self.right)));
        }
        if self.left > 0 {
            parts.push(format!("{} broke at or below {} limit (left-censored)", self.left, their(self.left)));
        }
        if self.interval > 0 {
            parts.push(format!("{} broke within a class (interval)", self.interval));
        }
        format!("{} {what}: {}", self.total(), parts.join(", "))
    }
}

impl Censoring {
    /// What the rows of one file say — each row's kind, value (`x`) and interval upper value
    /// (NaN for the others) — with the scheme of the module docs: an exact or left-censored
    /// row's right limit is the file's largest right limit (none without right-censored rows),
    /// a right-censored row's its own; a left-censored row's left limit its own; an interval
    /// row's edges every end of the file's intervals. None when every row is exact.
    pub fn of_rows(kind: Vec<Censor>, x: &[f64], upper: Vec<f64>) -> Option<Censoring> {
        if kind.iter().all(|k| *k == Censor::Exact) {
            return None;
        }
        let n = kind.len();
        let rig = (0..n).filter(|&i| kind[i] == Censor::Right).map(|i| x[i]).fold(f64::NEG_INFINITY, f64::max);
        let rig = if rig.is_finite() { rig } else { f64::INFINITY };
        let right_draws = random_limits(&kind, x);
        let mut ends: Vec<f64> = (0..n).filter(|&i| kind[i] == Censor::Interval).flat_map(|i| [x[i], upper[i]]).collect();
        ends.sort_by(f64::total_cmp);
        ends.dedup();
        let scheme = Scheme {
            right: (0..n).map(|i| if kind[i] == Censor::Right { x[i] } else { rig }).collect(),
            left: (0..n).map(|i| if kind[i] == Censor::Left { x[i] } else { 0.0 }).collect(),
            edges: (0..n).map(|i| if kind[i] == Censor::Interval { ends.clone() } else { Vec::new() }).collect(),
            right_draws,
        };
        Some(Censoring { kind, upper, scheme: Arc::new(scheme) })
    }
}

/// The limits an exact row's redraw is censored at where the recorded right limits differ
/// (module docs): the reverse Kaplan–Meier estimate Ĝ of the limits — right-censored rows'
/// limits are its events, exact rows' values censor it (a break at x says the limit lay above
/// x) — and for each exact row Ĝ given a limit above its value, with the mass Ĝ leaves beyond
/// the largest recorded limit as no limit (∞). Empty for every row where the file has one
/// recorded limit or none (the rig's limit is then every exact row's), and for other rows.
fn random_limits(kind: &[Censor], x: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let n = kind.len();
    let mut limits: Vec<f64> = (0..n).filter(|&i| kind[i] == Censor::Right).map(|i| x[i]).collect();
    limits.sort_by(f64::total_cmp);
    limits.dedup();
    if limits.len() < 2 {
        return vec![Vec::new(); n];
    }
    // Ĝ's masses at the distinct limits: at risk at u, every row whose value (a limit or a
    // break, both for exact and left rows) is ≥ u.
    let times: Vec<f64> = (0..n).filter(|&i| matches!(kind[i], Censor::Right | Censor::Exact)).map(|i| x[i]).collect();
    let mut survive = 1.0;
    let mut mass = Vec::with_capacity(limits.len());
    for &u in &limits {
        let at_risk = times.iter().filter(|t| **t >= u).count() as f64;
        let events = (0..n).filter(|&i| kind[i] == Censor::Right && x[i] == u).count() as f64;
        let next = survive * (1.0 - events / at_risk);
        mass.push((u, survive - next));
        survive = next;
    }
    (0..n)
        .map(|i| {
            if kind[i] != Censor::Exact {
                return Vec::new();
            }
            let mut choices: Vec<(f64, f64)> = mass.iter().copied().filter(|(u, p)| *u > x[i] && *p > 0.0).collect();
            if survive > 0.0 {
                choices.push((f64::INFINITY, survive));
            }
            let total: f64 = choices.iter().map(|c| c.1).sum();
            if total > 0.0 {
                choices.iter_mut().for_each(|c| c.1 /= total);
            }
            choices
        })
        .collect()
}

/// The rows of a table whose row i counts `counts[i]` specimens, one entry per specimen (row i
/// repeated `counts[i]` times, in row order; a row counting 0 specimens gives none).
pub fn expand(counts: &[usize]) -> Vec<usize> {
    counts.iter().enumerate().flat_map(|(i, &k)| std::iter::repeat_n(i, k)).collect()
}

impl Observations {
    /// Every row exact.
    pub fn exact(x: Vec<f64>) -> Observations {
        Observations { x, censoring: None }
    }

    /// The borrowed view.
    pub fn view(&self) -> Obs<'_> {
        Obs { x: &self.x, censoring: self.censoring.as_ref() }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there is no row.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// The rows `rows`, in that order (their limits with them).
    pub fn rows(&self, rows: &[usize]) -> Observations {
        self.view().rows(rows)
    }

    /// Appends the rows of new tests, each (value, right limit, broke): a row that broke at its
    /// value under a rig's limit (∞: none), or one that did not break by the limit (its value is
    /// the limit; right-censored). A redraw of an appended row is censored at its limit, type I,
    /// as the test would have censored it. The rows already held keep what they say.
    pub fn append_tested(&mut self, rows: impl IntoIterator<Item = (f64, f64, bool)>) {
        let rows: Vec<(f64, f64, bool)> = rows.into_iter().collect();
        let start = self.x.len();
        self.x.extend(rows.iter().map(|r| r.0));
        if self.censoring.is_none() && rows.iter().all(|&(_, limit, broke)| broke && limit == f64::INFINITY) {
            return;
        }
        let c = self.censoring.get_or_insert_with(|| Censoring {
            kind: vec![Censor::Exact; start],
            upper: vec![f64::NAN; start],
            scheme: Arc::new(Scheme { right: vec![f64::INFINITY; start], left: vec![0.0; start], edges: vec![Vec::new(); start], right_draws: vec![Vec::new(); start] }),
        });
        let mut s = (*c.scheme).clone();
        for &(_, limit, broke) in &rows {
            c.kind.push(if broke { Censor::Exact } else { Censor::Right });
            c.upper.push(f64::NAN);
            s.right.push(limit);
            s.left.push(0.0);
            s.edges.push(Vec::new());
            s.right_draws.push(Vec::new());
        }
        c.scheme = Arc::new(s);
    }

    /// Every row's values mapped by `f` (a monotone increasing change of units: the limits and
    /// class edges move with them).
    pub fn map(&self, f: impl Fn(usize, f64) -> f64) -> Observations {
        let x = self.x.iter().enumerate().map(|(i, v)| f(i, *v)).collect();
        let censoring = self.censoring.as_ref().map(|c| Censoring {
            kind: c.kind.clone(),
            upper: c.upper.iter().enumerate().map(|(i, v)| if v.is_nan() { *v } else { f(i, *v) }).collect(),
            scheme: Arc::new(Scheme {
                right: c.scheme.right.iter().enumerate().map(|(i, v)| if v.is_finite() { f(i, *v) } else { *v }).collect(),
                left: c.scheme.left.iter().enumerate().map(|(i, v)| if *v > 0.0 { f(i, *v) } else { *v }).collect(),
                edges: c.scheme.edges.iter().enumerate().map(|(i, e)| e.iter().map(|v| f(i, *v)).collect()).collect(),
                right_draws: c.scheme.right_draws.iter().enumerate().map(|(i, d)| d.iter().map(|&(v, p)| (if v.is_finite() { f(i, v) } else { v }, p)).collect()).collect(),
            }),
        });
        Observations { x, censoring }
    }
}

/// Values collected are rows that broke at them (exact).
impl FromIterator<f64> for Observations {
    fn from_iter<I: IntoIterator<Item = f64>>(iter: I) -> Self {
        Observations::exact(iter.into_iter().collect())
    }
}

impl<'a> Obs<'a> {
    /// Every row exact.
    pub fn exact(x: &'a [f64]) -> Obs<'a> {
        Obs { x, censoring: None }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there is no row.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Row i's kind.
    #[inline]
    pub fn kind(&self, i: usize) -> Censor {
        self.censoring.map_or(Censor::Exact, |c| c.kind[i])
    }

    /// Row i's upper value (an interval's; NaN for the other kinds).
    #[inline]
    pub fn upper(&self, i: usize) -> f64 {
        self.censoring.map_or(f64::NAN, |c| c.upper[i])
    }

    /// The rows as failure origin `level` sees them, where row i failed from `origin[i]`
    /// (ASTM C1239's estimate per origin, the other origins censored): its own breaks and the
    /// rows that did not break as they are, another origin's break right-censored at its value
    /// (or its class's lower end: it survived this origin's flaws at least that far), a break
    /// at or below a value from another origin left out (it says nothing of this origin); and
    /// how many of the rows are breaks from `level`.
    pub fn of_origin(&self, origin: &[String], level: &str) -> (Observations, usize) {
        let (mut xs, mut kinds, mut upper) = (Vec::new(), Vec::new(), Vec::new());
        let mut breaks = 0;
        for i in 0..self.len() {
            let k = self.kind(i);
            if origin[i] == level || k == Censor::Right {
                breaks += usize::from(k != Censor::Right);
                xs.push(self.x[i]);
                kinds.push(k);
                upper.push(self.upper(i));
            } else if k != Censor::Left {
                xs.push(self.x[i]);
                kinds.push(Censor::Right);
                upper.push(f64::NAN);
            }
        }
        let censoring = Censoring::of_rows(kinds, &xs, upper);
        (Observations { x: xs, censoring }, breaks)
    }

    /// Whether every row is exact.
    pub fn complete(&self) -> bool {
        self.censoring.is_none_or(|c| c.kind.iter().all(|k| *k == Censor::Exact))
    }

    /// The number of rows of each kind.
    pub fn tally(&self) -> Tally {
        let mut t = Tally::default();
        for i in 0..self.len() {
            match self.kind(i) {
                Censor::Exact => t.exact += 1,
                Censor::Right => t.right += 1,
                Censor::Left => t.left += 1,
                Censor::Interval => t.interval += 1,
            }
        }
        t
    }

    /// Owned copy.
    pub fn to_owned(&self) -> Observations {
        Observations { x: self.x.to_vec(), censoring: self.censoring.cloned() }
    }

    /// The rows `rows`, in that order (their limits with them).
    pub fn rows(&self, rows: &[usize]) -> Observations {
        let x = rows.iter().map(|&i| self.x[i]).collect();
        let censoring = self.censoring.map(|c| Censoring {
            kind: rows.iter().map(|&i| c.kind[i]).collect(),
            upper: rows.iter().map(|&i| c.upper[i]).collect(),
            scheme: Arc::new(Scheme {
                right: rows.iter().map(|&i| c.scheme.right[i]).collect(),
                left: rows.iter().map(|&i| c.scheme.left[i]).collect(),
                edges: rows.iter().map(|&i| c.scheme.edges[i].clone()).collect(),
                right_draws: rows.iter().map(|&i| c.scheme.right_draws[i].clone()).collect(),
            }),
        });
        Observations { x, censoring }
    }

    /// The values of one redraw, one per row, censored as the campaign censored each row
    /// (module docs); an exact row's limit drawn from `rng` where the recorded limits differ
    /// (nothing is drawn otherwise). Without censoring, the values themselves.
    pub fn censor<R: rand::Rng + ?Sized>(&self, redraw: Vec<f64>, rng: &mut R) -> Observations {
        let Some(c) = self.censoring else { return Observations::exact(redraw) };
        let n = redraw.len();
        let mut x = Vec::with_capacity(n);
        let mut kind = Vec::with_capacity(n);
        let mut upper = vec![f64::NAN; n];
        for (i, v) in redraw.into_iter().enumerate() {
            let s = &c.scheme;
            if c.kind[i] == Censor::Interval {
                let e = &s.edges[i];
                match e.iter().position(|b| v < *b) {
                    Some(0) => {
                        x.push(e[0]);
                        kind.push(Censor::Left);
                    }
                    Some(k) => {
                        x.push(e[k - 1]);
                        upper[i] = e[k];
                        kind.push(Censor::Interval);
                    }
                    None => {
                        x.push(e[e.len() - 1]);
                        kind.push(Censor::Right);
                    }
                }
            } else {
                let limit = draw_limit(&s.right_draws[i], s.right[i], rng);
                if v > limit {
                    x.push(limit);
                    kind.push(Censor::Right);
                } else if v <= s.left[i] {
                    x.push(s.left[i]);
                    kind.push(Censor::Left);
                } else {
                    x.push(v);
                    kind.push(Censor::Exact);
                }
            }
        }
        Observations { x, censoring: Some(Censoring { kind, upper, scheme: c.scheme.clone() }) }
    }

    /// ln P(row i) under a law given by its log density and log survival function:
    /// ln f(x), ln S(x), ln F(x) = ln(1 − S(x)) or ln[S(x) − S(x_u)] by the row's kind
    /// (the table of the module docs), computed from ln S without cancellation.
    pub fn ln_prob(&self, i: usize, ln_pdf: impl Fn(f64) -> f64, ln_sf: impl Fn(f64) -> f64) -> f64 {
        let x = self.x[i];
        match self.kind(i) {
            Censor::Exact => ln_pdf(x),
            Censor::Right => ln_sf(x),
            Censor::Left => ln_one_minus_exp(ln_sf(x)),
            Censor::Interval => {
                let (a, b) = (ln_sf(x), ln_sf(self.upper(i)));
                a + ln_one_minus_exp(b - a)
            }
        }
    }

    /// The probability-integral transform of row i under a law with CDF `cdf`, with `v` in
    /// [0, 1) picking a point within what the row allows: F(x) for an exact row;
    /// F(x) + v [1 − F(x)] (right), v F(x) (left), F(x) + v [F(x_u) − F(x)] (interval). With
    /// `v` uniform these are the randomised quantile residuals of Dunn & Smyth (1996): uniform
    /// on (0, 1) under the true law, censored rows included.
    pub fn pit(&self, i: usize, cdf: impl Fn(f64) -> f64, v: f64) -> f64 {
        let f = cdf(self.x[i]);
        match self.kind(i) {
            Censor::Exact => f,
            Censor::Right => f + v * (1.0 - f),
            Censor::Left => v * f,
            Censor::Interval => f + v * (cdf(self.upper(i)) - f),
        }
    }

    /// A value standing for row i where one number must (least-squares starts, a median for
    /// scaling): the value of an exact or right-censored row, the limit of a left-censored row,
    /// the geometric mean of an interval's ends.
    pub fn point(&self, i: usize) -> f64 {
        match self.kind(i) {
            Censor::Interval => (self.x[i] * self.upper(i)).sqrt(),
            _ => self.x[i],
        }
    }
}

/// A redraw's right limit: `fixed`, or one of `choices` (limit, probability) by inversion of a
/// uniform from `rng` where there are several.
fn draw_limit<R: rand::Rng + ?Sized>(choices: &[(f64, f64)], fixed: f64, rng: &mut R) -> f64 {
    match choices {
        [] => fixed,
        [(only, _)] => *only,
        _ => {
            let u: f64 = rng.random();
            let mut acc = 0.0;
            for &(v, p) in choices {
                acc += p;
                if u < acc {
                    return v;
                }
            }
            choices[choices.len() - 1].0
        }
    }
}

/// ln(1 − e^a) for a ≤ 0, without cancellation (Mächler 2012): ln(−expm1(a)) near 0,
/// ln1p(−e^a) below −ln 2.
pub fn ln_one_minus_exp(a: f64) -> f64 {
    if a > -std::f64::consts::LN_2 { (-a.exp_m1()).ln() } else { (-a.exp()).ln_1p() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn appended_tests_keep_their_limits_and_the_held_rows_theirs() {
        // New tests without a limit on complete data: still complete.
        let mut o = Observations::exact(vec![1.0, 2.0]);
        o.append_tested([(3.0, f64::INFINITY, true)]);
        assert_eq!(o, Observations::exact(vec![1.0, 2.0, 3.0]));
        // At a rig's limit of 4: one broke at 3.5, one did not break by 4.
        o.append_tested([(3.5, 4.0, true), (4.0, 4.0, false)]);
        let c = o.censoring.as_ref().unwrap();
        assert_eq!(c.kind, [Censor::Exact, Censor::Exact, Censor::Exact, Censor::Exact, Censor::Right]);
        assert_eq!(c.scheme.right, [f64::INFINITY, f64::INFINITY, f64::INFINITY, 4.0, 4.0]);
        assert_eq!(o.view().tally(), Tally { exact: 4, right: 1, left: 0, interval: 0 });
        // A redraw censors the new rows at 4 and the held rows nowhere.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let r = o.view().censor(vec![9.0; 5], &mut rng);
        assert_eq!(r.x, [9.0, 9.0, 9.0, 4.0, 4.0]);
        assert_eq!(r.censoring.unwrap().kind, [Censor::Exact, Censor::Exact, Censor::Exact, Censor::Right, Censor::Right]);
        // Held censoring is kept.
        let mut h = Observations { x: vec![1.0, 5.0], censoring: Censoring::of_rows(vec![Censor::Exact, Censor::Right], &[1.0, 5.0], vec![f64::NAN; 2]) };
        h.append_tested([(2.0, 3.0, true)]);
        let c = h.censoring.unwrap();
        assert_eq!((c.kind, c.scheme.right.clone()), (vec![Censor::Exact, Censor::Right, Censor::Exact], vec![5.0, 5.0, 3.0]));
    }

    fn scheme() -> Censoring {
        Censoring {
            kind: vec![Censor::Exact, Censor::Right, Censor::Left, Censor::Interval],
            upper: vec![f64::NAN, f64::NAN, f64::NAN, 3.0],
            scheme: Arc::new(Scheme { right: vec![5.0, 5.0, f64::INFINITY, f64::INFINITY], left: vec![0.0, 0.0, 1.0, 0.0], edges: vec![vec![], vec![], vec![], vec![1.0, 2.0, 3.0, 4.0]], right_draws: vec![Vec::new(); 4] }),
        }
    }

    #[test]
    fn a_redraw_is_censored_as_each_row_was() {
        let c = scheme();
        let x = [2.0, 5.0, 1.0, 2.0];
        let o = Obs { x: &x, censoring: Some(&c) };
        // Row 0 beyond the rig limit: right at 5; row 1 below it: exact; row 2 under its
        // left limit: left at 1; row 3 in the class [3, 4).
        let r = o.censor(vec![6.0, 4.5, 0.5, 3.5], &mut rand::rng());
        assert_eq!(r.x, [5.0, 4.5, 1.0, 3.0]);
        let rc = r.censoring.as_ref().unwrap();
        assert_eq!(rc.kind, [Censor::Right, Censor::Exact, Censor::Left, Censor::Interval]);
        assert_eq!(rc.upper[3], 4.0);
        // Outside every class: left below the lowest edge, right above the highest.
        let r = o.censor(vec![1.0, 1.0, 2.0, 0.2], &mut rand::rng());
        assert_eq!((r.x[3], r.censoring.as_ref().unwrap().kind[3]), (1.0, Censor::Left));
        let r = o.censor(vec![1.0, 1.0, 2.0, 9.0], &mut rand::rng());
        assert_eq!((r.x[3], r.censoring.as_ref().unwrap().kind[3]), (4.0, Censor::Right));
        assert_eq!(o.tally(), Tally { exact: 1, right: 1, left: 1, interval: 1 });
    }

    #[test]
    fn ln_prob_is_the_kind_s_probability() {
        // Exponential law with rate 1: S(x) = e^(−x).
        let c = scheme();
        let x = [2.0, 5.0, 1.0, 2.0];
        let o = Obs { x: &x, censoring: Some(&c) };
        let (pdf, sf) = (|x: f64| -x, |x: f64| -x);
        assert!((o.ln_prob(0, pdf, sf) + 2.0).abs() < 1e-15);
        assert!((o.ln_prob(1, pdf, sf) + 5.0).abs() < 1e-15);
        assert!((o.ln_prob(2, pdf, sf) - (1.0 - (-1.0f64).exp()).ln()).abs() < 1e-15);
        assert!((o.ln_prob(3, pdf, sf) - ((-2.0f64).exp() - (-3.0f64).exp()).ln()).abs() < 1e-14);
        // Far in the tail ln(1 − e^a) keeps its digits.
        assert!((ln_one_minus_exp(-1e-20) - (1e-20f64).ln()).abs() < 1e-12);
        assert!((ln_one_minus_exp(-50.0) + (-50.0f64).exp()).abs() < 1e-30);
    }

    #[test]
    fn a_file_s_rows_give_their_scheme() {
        let kind = vec![Censor::Exact, Censor::Right, Censor::Right, Censor::Interval, Censor::Interval, Censor::Left];
        let x = [3.0, 4.0, 5.0, 1.0, 2.0, 0.5];
        let c = Censoring::of_rows(kind, &x, vec![f64::NAN, f64::NAN, f64::NAN, 2.0, 3.0, f64::NAN]).unwrap();
        // The rig's limit is the largest right limit; each right-censored row keeps its own.
        assert_eq!(c.scheme.right, [5.0, 4.0, 5.0, 5.0, 5.0, 5.0]);
        assert_eq!(c.scheme.left, [0.0, 0.0, 0.0, 0.0, 0.0, 0.5]);
        assert_eq!(c.scheme.edges[3], [1.0, 2.0, 3.0]);
        assert!(c.scheme.edges[0].is_empty());
        assert_eq!(Censoring::of_rows(vec![Censor::Exact; 2], &[1.0, 2.0], vec![f64::NAN; 2]), None);
        assert_eq!(expand(&[2, 0, 1]), [0, 0, 2]);
    }

    #[test]
    fn with_limits_of_their_own_an_exact_row_s_limit_follows_the_reverse_kaplan_meier_estimate() {
        // Breaks at 1 and 3, limits 2, 4 and 5: Ĝ has at risk 4 at 2 (one event: 1/4), 2 at 4
        // (3/4 · 1/2 = 3/8) and 1 at 5 (the rest, 3/8). The break at 1 may have been stopped at
        // 2, 4 or 5 in those proportions; the break at 3 at 4 or 5, one half each.
        let kind = vec![Censor::Exact, Censor::Right, Censor::Exact, Censor::Right, Censor::Right];
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        let c = Censoring::of_rows(kind, &x, vec![f64::NAN; 5]).unwrap();
        let close = |a: &[(f64, f64)], b: &[(f64, f64)]| a.len() == b.len() && a.iter().zip(b).all(|(p, q)| p.0 == q.0 && (p.1 - q.1).abs() < 1e-12);
        assert!(close(&c.scheme.right_draws[0], &[(2.0, 0.25), (4.0, 0.375), (5.0, 0.375)]), "{:?}", c.scheme.right_draws[0]);
        assert!(close(&c.scheme.right_draws[2], &[(4.0, 0.5), (5.0, 0.5)]), "{:?}", c.scheme.right_draws[2]);
        assert!(c.scheme.right_draws[1].is_empty());
        // One recorded limit (twice): every exact row's is the rig's, nothing is drawn.
        let one = Censoring::of_rows(vec![Censor::Exact, Censor::Right, Censor::Right], &[1.0, 4.0, 4.0], vec![f64::NAN; 3]).unwrap();
        assert!(one.scheme.right_draws.iter().all(|d| d.is_empty()) && one.scheme.right[0] == 4.0);
        // Redraws of row 0 at 4.5 are censored at 2 or 4 in 62.5 % of them.
        let o = Obs { x: &x, censoring: Some(&c) };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let k = 20_000;
        let cut = (0..k).filter(|_| o.censor(vec![4.5, 1.0, 1.0, 1.0, 1.0], &mut rng).censoring.unwrap().kind[0] == Censor::Right).count();
        assert!((cut as f64 / k as f64 - 0.625).abs() < 0.015, "{cut} of {k}");
    }

    #[test]
    fn rows_and_maps_keep_limits_aligned() {
        let c = scheme();
        let x = [2.0, 5.0, 1.0, 2.0];
        let o = Obs { x: &x, censoring: Some(&c) };
        let sub = o.rows(&[3, 1]);
        let sc = sub.censoring.as_ref().unwrap();
        assert_eq!(sc.kind, [Censor::Interval, Censor::Right]);
        assert_eq!(sc.scheme.edges[0], [1.0, 2.0, 3.0, 4.0]);
        let doubled = o.to_owned().map(|_, v| 2.0 * v);
        let dc = doubled.censoring.as_ref().unwrap();
        assert_eq!(doubled.x, [4.0, 10.0, 2.0, 4.0]);
        assert_eq!((dc.upper[3], dc.scheme.right[0], dc.scheme.right[2], dc.scheme.left[2]), (6.0, 10.0, f64::INFINITY, 2.0));
    }
}
