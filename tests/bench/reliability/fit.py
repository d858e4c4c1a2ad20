"""Peer fits for tests/strength_factors.rs: the `reliability` package's two-parameter Weibull
MLE on the shipped real data sets (values as the files hold them: GPa for the fibres, the
original units — read as MPa — for the Jahanmir bend bars). Run:

    python3 -m venv /tmp/peer && /tmp/peer/bin/pip install reliability
    /tmp/peer/bin/python tests/bench/reliability/fit.py

and pin the printed numbers in the test (no Python at test time)."""
import csv
from reliability.Fitters import Fit_Weibull_2P

def column(path, name, where=None):
    with open(path) as f:
        return [float(r[name]) for r in csv.DictReader(f) if where is None or where(r)]

sets = {"glass": column("datasets/real/smith_naylor_glass_fibres.csv", "strength_original_units")}
for L in ("10", "20", "50"):
    sets[f"carbon_{L}mm"] = column("datasets/real/bader_priest_carbon_fibres.csv", "strength_gpa", lambda r, L=L: r["gauge_length_mm"] == L)
sets["carbon_pooled"] = column("datasets/real/bader_priest_carbon_fibres.csv", "strength_gpa")
J = "datasets/real/jahanmir_silicon_nitride_bend_bars.csv"
sets["jahanmir"] = column(J, "strength_original_units")
for b in ("1", "2"):
    sets[f"jahanmir_batch{b}"] = column(J, "strength_original_units", lambda r, b=b: r["batch"] == b)
for k, x in sets.items():
    f = Fit_Weibull_2P(failures=x, show_probability_plot=False, print_results=False, method="MLE")
    print(f"{k}: n = {len(x)}, beta (m) = {f.beta:.10f}, alpha (scale, GPa) = {f.alpha:.10f}, loglik = {f.loglik:.10f}")

# Two flaw populations (pinned in PEER_FLAWS).
from reliability.Fitters import Fit_Weibull_Mixture, Fit_Weibull_CR
for k in ("glass", "carbon_pooled", "jahanmir"):
    x = sets[k]
    m = Fit_Weibull_Mixture(failures=x, show_probability_plot=False, print_results=False)
    print(f"{k} mixture: p = {m.proportion_1:.10f}, alpha_1 = {m.alpha_1:.10f}, beta_1 = {m.beta_1:.10f}, alpha_2 = {m.alpha_2:.10f}, beta_2 = {m.beta_2:.10f}, loglik = {m.loglik:.10f}")
    c = Fit_Weibull_CR(failures=x, show_probability_plot=False, print_results=False)
    print(f"{k} competing risks: alpha_1 = {c.alpha_1:.10f}, beta_1 = {c.beta_1:.10f}, alpha_2 = {c.alpha_2:.10f}, beta_2 = {c.beta_2:.10f}, loglik = {c.loglik:.10f}")
