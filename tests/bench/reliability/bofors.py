"""Peer fits for tests/real_grouped.rs: Weibull's (1951) yield strengths of Bofors steel
(datasets/real/weibull_bofors_steel_yield.csv, 389 specimens in 10 classes, kgf/mm²), fitted by
the `reliability` package and by surpyval:

* the class values as exact strengths, each counted (reliability's Fit_Weibull_2P on the 389
  values; surpyval with x and n) — two and three parameters;
* the classes as intervals (each value ± 0.6375 kgf/mm², half the class width 1.275; surpyval
  with xl/xr and n) — two and three parameters.

Log-likelihoods are of the density in kgf/mm⁻¹ for exact values, of probabilities for classes.
Run:

    python3 -m venv /tmp/peer && /tmp/peer/bin/pip install reliability surpyval
    /tmp/peer/bin/python tests/bench/reliability/bofors.py

and pin the printed numbers in the test (no Python at test time)."""
import csv, os, warnings
import numpy as np

warnings.filterwarnings("ignore")
here = os.path.dirname(os.path.abspath(__file__))
rows = list(csv.DictReader(open(os.path.join(here, "../../../datasets/real/weibull_bofors_steel_yield.csv"))))
x = np.array([float(r["yield_strength_kgf_mm2"]) for r in rows])
n = np.array([int(r["count"]) for r in rows])
lo = np.array([float(r["class_lower_kgf_mm2"]) for r in rows])
hi = np.array([float(r["class_upper_kgf_mm2"]) for r in rows])
print(f"specimens: {n.sum()} in {len(n)} classes")

from reliability.Fitters import Fit_Weibull_2P
f = Fit_Weibull_2P(failures=np.repeat(x, n), show_probability_plot=False, print_results=False, method="MLE")
print(f"exact, 2 parameters (reliability): m = {f.beta:.10f}, sigma = {f.alpha:.10f}, loglik = {f.loglik:.10f}")

import surpyval
m = surpyval.Weibull.fit(x=x, n=n)
print(f"exact, 2 parameters (surpyval): m = {m.params[1]:.10f}, sigma = {m.params[0]:.10f}, loglik = {-m.neg_ll():.10f}")
m = surpyval.Weibull.fit(x=x, n=n, offset=True)
print(f"exact, 3 parameters (surpyval): gamma = {m.gamma:.10f}, m = {m.params[1]:.10f}, sigma = {m.params[0]:.10f}, loglik = {-m.neg_ll():.10f}")
xi = np.vstack([lo, hi]).T
m = surpyval.Weibull.fit(x=xi, n=n)
print(f"classes, 2 parameters (surpyval): m = {m.params[1]:.10f}, sigma = {m.params[0]:.10f}, loglik = {-m.neg_ll():.10f}")
m = surpyval.Weibull.fit(x=xi, n=n, offset=True)
print(f"classes, 3 parameters (surpyval): gamma = {m.gamma:.10f}, m = {m.params[1]:.10f}, sigma = {m.params[0]:.10f}, loglik = {-m.neg_ll():.10f}")
