#!/usr/bin/env python3
"""emcee on the Rosenbrock banana of partlife's MCMC benchmark (same walkers, steps, burn-in).

Usage: python3 tests/bench/emcee/banana.py /tmp/emcee_banana.csv
Prints the sampling time; then: partlife bench --mcmc --chain /tmp/emcee_banana.csv:SECONDS
computes emcee's ESS with partlife's estimator, so both samplers are judged alike.
Needs `pip install emcee`; emcee's code is not part of partlife.
"""
import sys
import time

import emcee
import numpy as np


def log_prob(x):
    return -(100.0 * (x[1] - x[0] ** 2) ** 2 + (1.0 - x[0]) ** 2) / 20.0


rng = np.random.default_rng(6)
p0 = np.array([1.0, 1.0]) + 0.1 * (rng.random((32, 2)) - 0.5)
sampler = emcee.EnsembleSampler(32, 2, log_prob)
t = time.time()
sampler.run_mcmc(p0, 42000, progress=False)
seconds = time.time() - t
chain = sampler.get_chain(discard=2000)  # (steps, walkers, 2)
with open(sys.argv[1], "w") as f:
    f.write("step,walker,x1,x2\n")
    for s in range(chain.shape[0]):
        for w in range(chain.shape[1]):
            f.write(f"{s},{w},{float(chain[s, w, 0])!r},{float(chain[s, w, 1])!r}\n")
print(f"emcee {emcee.__version__}: {seconds:.2f} s for 32 walkers x 42000 steps")
