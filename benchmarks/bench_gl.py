"""Time fohw.gl_difference (a new order at every call) against numpy.convolve and its FFT floor.

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_gl.py [--quick]

The floor is the zero-padded 3-FFT linear convolution written out: the weights by the
recurrence, rfft of the signal and of the weights, product, irfft, cut to N (what
gl_difference computes, without its checks). Every number comes from this one run: the median
of several repeats per size. The machine is shared, so compare the ratios, not the absolute
times. numpy.convolve is O(N^2) and is only timed up to N = 10^5.
"""

import argparse
import os
import platform
import time

import numpy as np
import scipy.fft

import fohw

# ruff: noqa: B023   (the timed lambdas run inside their loop iteration)


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def three_fft(x, alpha):
    n = len(x)
    nfft = scipy.fft.next_fast_len(2 * n - 1, real=True)
    w = np.empty(n)
    w[0] = 1.0
    np.cumprod(1.0 - (alpha + 1.0) / np.arange(1.0, n), out=w[1:])
    return scipy.fft.irfft(scipy.fft.rfft(x, n=nfft) * scipy.fft.rfft(w, n=nfft), n=nfft)[:n]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="sizes up to 10^5 and fewer repeats")
    args = ap.parse_args(argv)
    sizes = [10**3, 10**4, 10**5] if args.quick else [10**3, 10**4, 10**5, 10**6]
    print(f"# gl_difference benchmark: numpy {np.__version__}, scipy {scipy.__version__}, "
          f"{platform.machine()}, python {platform.python_version()}")
    print(f"# medians; new order at every call; OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")
    print("| N | repeats | gl_difference [ms] | numpy.convolve [ms] | 3-FFT floor [ms] | "
          "convolve / gl | gl / floor |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    rng = np.random.default_rng(0)
    for n in sizes:
        x = rng.standard_normal(n)
        repeats = 3 if (args.quick or n >= 10**6) else 7
        orders = iter(np.linspace(0.1, 0.9, 2 * repeats))
        t_gl = median_time(lambda: fohw.gl_difference(x, next(orders)), repeats)
        orders = iter(np.linspace(0.1, 0.9, 2 * repeats))
        t_fft = median_time(lambda: three_fft(x, next(orders)), repeats)
        if n <= 10**5:
            w = fohw.gl_weights(0.6, n)
            t_conv = median_time(lambda: np.convolve(x, w)[:n], 1 if n >= 10**5 else repeats)
            conv = f"{1e3 * t_conv:.2f}"
            ratio = f"{t_conv / t_gl:.1f}"
        else:
            conv, ratio = "(not run: O(N^2))", "–"
        print(f"| {n:.0e} | {repeats} | {1e3 * t_gl:.2f} | {conv} | {1e3 * t_fft:.2f} | {ratio} | "
              f"{t_gl / t_fft:.2f} |")


if __name__ == "__main__":
    main()
