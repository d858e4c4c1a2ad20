"""Peer fits for tests/censoring.rs: the two-parameter Weibull MLE of a censored sample by the
`reliability` package (right-censored) and by surpyval (right, left and interval rows together).
The 40 values are 40 draws of Weibull(m = 11.5, σ = 1) (Python's random, seed 52, rounded to 4
decimals), held here and in the test. Run:

    python3 -m venv /tmp/peer && /tmp/peer/bin/pip install reliability surpyval
    /tmp/peer/bin/python tests/bench/reliability/censored.py

and pin the printed numbers in the test (no Python at test time)."""
X = [1.1239, 0.7784, 1.0226, 0.9647, 1.0951, 0.9451, 1.0836, 0.8587, 1.1552, 0.9467, 0.8703, 0.9283, 0.9997, 0.7467, 0.9398, 0.6765, 0.7954, 0.8642, 0.8901, 0.9058, 1.0362, 0.9475, 1.0597, 1.0746, 1.0733, 1.0986, 0.9867, 1.0093, 1.0681, 0.9791, 0.8496, 0.9736, 0.9759, 0.8687, 0.8166, 0.8709, 1.0156, 1.0458, 1.0058, 0.9503]
LIMIT = 1.05

# Right-censored at the rig's limit: reliability.
from reliability.Fitters import Fit_Weibull_2P
failures = [v for v in X if v <= LIMIT]
censored = [LIMIT for v in X if v > LIMIT]
f = Fit_Weibull_2P(failures=failures, right_censored=censored, show_probability_plot=False, print_results=False, method="MLE")
print(f"right-censored (reliability): broken {len(failures)}, not broken {len(censored)}, beta (m) = {f.beta:.10f}, alpha = {f.alpha:.10f}, loglik = {f.loglik:.10f}")

# Every kind: below 0.8 left-censored at 0.8, in [0.9, 1.0) the class (0.9, 1.0), above the
# limit right-censored, the rest exact: surpyval (x, c: 0 exact, 1 right, -1 left, 2 interval).
import surpyval
x, c = [], []
for v in X:
    if v < 0.8:
        x.append([0.8, 0.8]); c.append(-1)
    elif 0.9 <= v < 1.0:
        x.append([0.9, 1.0]); c.append(2)
    elif v > LIMIT:
        x.append([LIMIT, LIMIT]); c.append(1)
    else:
        x.append([v, v]); c.append(0)
m = surpyval.Weibull.fit(x=x, c=c)
print(f"every kind (surpyval): c counts {[c.count(k) for k in (0, 1, -1, 2)]}, beta (m) = {m.beta:.10f}, alpha = {m.alpha:.10f}, loglik = {-m.neg_ll():.10f}")
