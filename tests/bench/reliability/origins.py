"""Peer fits for tests/censoring.rs: Nelson's connection strengths
(datasets/real/nelson_connection_strength.csv, 20 specimens with their failure mode, counted),
each mode's two-parameter Weibull MLE with the other mode's breaks right-censored at their
strength (ASTM C1239's estimate per origin), and the fit of all 20 together, by the
`reliability` package. Log-likelihoods are of densities in the file's units. Run:

    python3 -m venv /tmp/peer && /tmp/peer/bin/pip install reliability
    /tmp/peer/bin/python tests/bench/reliability/origins.py

and pin the printed numbers in the test (no Python at test time)."""
import csv, math, os
from reliability.Fitters import Fit_Weibull_2P

here = os.path.dirname(os.path.abspath(__file__))
rows = list(csv.DictReader(open(os.path.join(here, "../../../datasets/real/nelson_connection_strength.csv"))))
x = [(float(r["strength_original_units"]), r["failure_mode"]) for r in rows for _ in range(int(r["count"]))]
total = 0.0
for mode in sorted({m for _, m in x}):
    f = Fit_Weibull_2P(failures=[v for v, m in x if m == mode], right_censored=[v for v, m in x if m != mode], show_probability_plot=False, print_results=False, method="MLE")
    total += f.loglik
    print(f"{mode}: breaks {sum(1 for _, m in x if m == mode)}, m = {f.beta:.10f}, sigma = {f.alpha:.10f}, loglik = {f.loglik:.10f}")
a = Fit_Weibull_2P(failures=[v for v, _ in x], show_probability_plot=False, print_results=False, method="MLE")
modes = sorted({m for _, m in x})
# One modulus, a scale per origin: the one-law fit plus the multinomial of the origins' counts.
shared = a.loglik + sum(c * math.log(c / len(x)) for c in (sum(1 for _, m in x if m == mode) for mode in modes))
print(f"all {len(x)}: m = {a.beta:.10f}, sigma = {a.alpha:.10f}, loglik = {a.loglik:.10f}; one modulus {shared:.10f}; LR = {2 * (total - shared):.10f}")
