"""Time fohw.gl_difference against numpy.convolve and a bare scipy.fft round trip.

Run:  python benchmarks/bench_gl.py [--quick]

Every number comes from this one run: the median of several repeats per size. The machine
is shared, so compare the ratios, not the absolute times. numpy.convolve is O(N^2) and is
only timed up to N = 10^5.
"""

import argparse
import platform
import time

import numpy as np
import scipy.fft

import fohw


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def bare_round_trip(x):
    nfft = scipy.fft.next_fast_len(2 * len(x) - 1, real=True)
    return scipy.fft.irfft(scipy.fft.rfft(x, n=nfft), n=nfft)[: len(x)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="sizes up to 10^5 and fewer repeats")
    args = ap.parse_args(argv)
    sizes = [10**3, 10**4, 10**5] if args.quick else [10**3, 10**4, 10**5, 10**6]
    alpha = 0.6
    print(f"# gl_difference benchmark: numpy {np.__version__}, scipy {scipy.__version__}, "
          f"{platform.machine()}, python {platform.python_version()}")
    print("| N | gl_difference [ms] | numpy.convolve [ms] | bare rfft/irfft [ms] | "
          "convolve / gl | gl / bare FFT |")
    print("|---:|---:|---:|---:|---:|---:|")
    rng = np.random.default_rng(0)
    for n in sizes:
        x = rng.standard_normal(n)
        repeats = 3 if (args.quick or n >= 10**6) else 7
        t_gl = median_time(lambda: fohw.gl_difference(x, alpha), repeats)
        t_fft = median_time(lambda: bare_round_trip(x), repeats)
        if n <= 10**5:
            w = fohw.gl_weights(alpha, n)
            t_conv = median_time(lambda: np.convolve(x, w)[:n], 1 if n >= 10**5 else repeats)
            conv = f"{1e3 * t_conv:.2f}"
            ratio = f"{t_conv / t_gl:.1f}"
        else:
            conv, ratio = "(not run: O(N^2))", "–"
        print(f"| {n:.0e} | {1e3 * t_gl:.2f} | {conv} | {1e3 * t_fft:.2f} | {ratio} | "
              f"{t_gl / t_fft:.2f} |")


if __name__ == "__main__":
    main()
