"""What the equal-error scripts (equal_error_mitsuba.py, equal_error_cycles.py) share: whole-process timing, the
relative RMSE against a renderer's own reference with the reference's noise taken out, and strata's time for the
peer's error, fitted and printed (docs/performance.md, "Speed at equal error")."""
import subprocess
import time

import numpy as np


def run_timed(cmd):
    """The wall-clock seconds of `cmd` as a whole process; its stdout is dropped, a failure raises."""
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return time.perf_counter() - start


def relative_rmse(image, reference, spp, reference_spp, mask=None):
    """sqrt(mean((x - ref)^2)) / mean(ref) over `mask` (every pixel by default). An `spp` image's error squared
    against a `reference_spp` reference over-counts by the reference's own noise, spp / reference_spp of it."""
    if mask is not None:
        image, reference = image[mask], reference[mask]
    mse = np.mean((image - reference) ** 2) / (1.0 + spp / reference_spp)
    return float(np.sqrt(mse) / np.mean(reference))


def equal_error_table(rows, peer):
    """From rows {"strata": {spp: (seconds, error)}, peer: {spp: (seconds, error)}}: strata's whole-process time
    fitted as a + b*spp (the least-squares line through its runs), and for each spp the time strata needs for the
    peer's error, at spp*(strata's error / peer's)^2 spp. Prints the table; returns (a, b, runs) for JSON."""
    spps = sorted(rows["strata"])
    times = np.array([rows["strata"][n][0] for n in spps])
    if len(spps) > 1:
        b, a = np.polyfit(spps, times, 1)
    else:
        a, b = 0.0, times[0] / spps[0]
    print(f"strata's time fitted: {a:.2f} s + {b * 1000:.1f} ms/spp")
    possessive = f"{peer}'" if peer.endswith("s") else f"{peer}'s"
    print(f"spp | strata s, rel. RMSE | {peer} s, rel. RMSE | strata's time for {possessive} error | ratio")
    runs = []
    for n in spps:
        (t_s, e_s), (t_p, e_p) = rows["strata"][n], rows[peer][n]
        # Near n spp error falls as 1/sqrt(spp) (stratified sampling falls faster, so this overestimates the
        # spp strata needs where it is behind, and underestimates where it is ahead).
        needed = n * (e_s / e_p) ** 2
        t_equal = a + b * needed
        print(f"{n:4d} | {t_s:6.2f} {e_s:.4f} | {t_p:6.2f} {e_p:.4f} | {t_equal:6.2f} s ({needed:.0f} spp) | "
              f"{t_equal / t_p:.2f}x")
        key = peer.lower()
        runs.append({"spp": n, "strata_s": t_s, "strata_rel_rmse": e_s, f"{key}_s": t_p, f"{key}_rel_rmse": e_p,
                     "strata_equal_error_s": t_equal, "ratio": t_equal / t_p})
    return a, b, runs
