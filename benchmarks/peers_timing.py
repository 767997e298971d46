"""The peers scripts' timing: the best of repeated runs within a time budget."""
import time


def best(f, budget=2.0, most=50, least=3):
    """(the least time of f() over at least `least` runs, at most `most`, within about `budget`
    seconds; f's last result)."""
    t, out, spent = [], None, 0.0
    while len(t) < most and (len(t) < least or spent < budget):
        t0 = time.perf_counter()
        out = f()
        dt = time.perf_counter() - t0
        t.append(dt)
        spent += dt
    return min(t), out
