"""Peers of aureole on the issue-5 workload, one per process.

python peers.py DIR PEER  times PEER on DIR/image.npy and DIR/kernel.npy
(median of 6 runs after a warm-up; for the rfft2 pipeline the kernel
spectrum is built outside the timing, like aureole's plan), checks the
result against DIR/result.npy (relative L2 below 1e-4) and prints one JSON
line with the times, the agreement and the peak memory of the process.
"""

import json
import resource
import sys
import time

import numpy as np


def fftconvolve(image, kernel, workers=None):
    import scipy.fft
    import scipy.signal

    def run():
        out = np.empty_like(image)
        for c in range(image.shape[0]):
            out[c] = scipy.signal.fftconvolve(image[c], kernel, mode="same")
        return out

    if workers is None:
        return run
    def with_workers():
        with scipy.fft.set_workers(workers):
            return run()
    return with_workers


def oaconvolve(image, kernel):
    import scipy.signal

    def run():
        out = np.empty_like(image)
        for c in range(image.shape[0]):
            out[c] = scipy.signal.oaconvolve(image[c], kernel, mode="same")
        return out
    return run


def filter2d(image, kernel):
    import cv2

    flipped = np.ascontiguousarray(kernel[::-1, ::-1])
    def run():
        out = np.empty_like(image)
        for c in range(image.shape[0]):
            out[c] = cv2.filter2D(image[c], -1, flipped, borderType=cv2.BORDER_CONSTANT)
        return out
    return run


def rfft2_pipeline(image, kernel):
    import scipy.fft

    _, h, w = image.shape
    kh, kw = kernel.shape
    shape = (scipy.fft.next_fast_len(h + kh - 1, real=True), scipy.fft.next_fast_len(w + kw - 1, real=True))
    spectrum = scipy.fft.rfft2(kernel, shape, workers=2)
    top, left = kh // 2, kw // 2
    def run():
        out = np.empty_like(image)
        for c in range(image.shape[0]):
            full = scipy.fft.irfft2(scipy.fft.rfft2(image[c], shape, workers=2) * spectrum, shape, workers=2)
            out[c] = full[top:top + h, left:left + w]
        return out
    return run


def fftw_pipeline(image, kernel):
    import pyfftw
    import scipy.fft

    _, h, w = image.shape
    kh, kw = kernel.shape
    shape = (scipy.fft.next_fast_len(h + kh - 1, real=True), scipy.fft.next_fast_len(w + kw - 1, real=True))
    real = pyfftw.empty_aligned(shape, dtype="float32")
    spectrum = pyfftw.empty_aligned((shape[0], shape[1] // 2 + 1), dtype="complex64")
    # Planned once, measured (up to a minute each), then reused like
    # aureole's plan; the backward transform normalises.
    flags = ("FFTW_MEASURE",)
    forward = pyfftw.FFTW(real, spectrum, axes=(0, 1), threads=2, flags=flags, planning_timelimit=60)
    backward = pyfftw.FFTW(spectrum, real, axes=(0, 1), direction="FFTW_BACKWARD", threads=2,
                           flags=flags, planning_timelimit=60)
    real[:] = 0
    real[:kh, :kw] = kernel
    forward()
    kernel_spectrum = spectrum.copy()
    top, left = kh // 2, kw // 2
    def run():
        out = np.empty_like(image)
        for c in range(image.shape[0]):
            real[:] = 0
            real[:h, :w] = image[c]
            forward()
            np.multiply(spectrum, kernel_spectrum, out=spectrum)
            backward()
            out[c] = real[top:top + h, left:left + w]
        return out
    return run


PEERS = {
    "scipy.signal.fftconvolve": lambda i, k: fftconvolve(i, k),
    "scipy.signal.fftconvolve (2 workers)": lambda i, k: fftconvolve(i, k, workers=2),
    "scipy.signal.oaconvolve": oaconvolve,
    "cv2.filter2D": filter2d,
    "numpy/scipy rfft2, cached kernel spectrum": rfft2_pipeline,
    "pyFFTW rfft2 (FFTW, 2 threads, measured plans), cached kernel spectrum": fftw_pipeline,
}


def main():
    directory, peer = sys.argv[1], sys.argv[2]
    image = np.load(f"{directory}/image.npy")
    kernel = np.load(f"{directory}/kernel.npy")
    reference = np.load(f"{directory}/result.npy").astype(np.float64)
    run = PEERS[peer](image, kernel)
    result = run()
    times = []
    for _ in range(6):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    difference = np.linalg.norm(result.astype(np.float64) - reference) / np.linalg.norm(reference)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"peer": peer, "median": float(np.median(times)), "min": min(times), "max": max(times),
                      "difference": float(difference), "peak_mb": peak_mb}))


if __name__ == "__main__":
    main()
