"""What the benchmark scripts share (imported from the scripts' own folder)."""
import time


def best(fn, repeat):
    """The least wall time, in s, of ``repeat`` calls of ``fn()`` (the machine is shared: the
    best run is the one least disturbed)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)
