"""SALib's Saltelli sampling + sobol.analyze on Ishigami at N = 2^14 (the same base size and
bootstrap count as `partlife bench --uq`), timed; prints the indices and their largest error.
Peer check only: SALib is not a dependency of partlife.  Usage: python3 ishigami.py"""
import time
import numpy as np
from SALib.sample import saltelli
from SALib.analyze import sobol
from SALib.test_functions import Ishigami

problem = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-np.pi, np.pi]] * 3}
S1 = np.array([0.313905, 0.442411, 0.0])
ST = np.array([0.557589, 0.442411, 0.243684])
t0 = time.perf_counter()
X = saltelli.sample(problem, 2**14, calc_second_order=False)
Y = Ishigami.evaluate(X)
res = sobol.analyze(problem, Y, calc_second_order=False, num_resamples=1000, conf_level=0.95, seed=1)
dt = time.perf_counter() - t0
err = max(np.max(np.abs(res["S1"] - S1)), np.max(np.abs(res["ST"] - ST)))
print(f"SALib {len(Y)} runs: {dt:.3f} s, S1 {np.round(res['S1'], 4)}, ST {np.round(res['ST'], 4)}, largest |S - exact| = {err:.4f}")
