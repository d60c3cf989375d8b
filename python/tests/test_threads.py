"""One compiled model from several Python threads; the GIL is released while integrating."""
import threading
import time

import numpy as np
import pytest

import kanesim


def test_threads_give_the_serial_results(examples):
    m = kanesim.load(examples / "double_pendulum.mech")
    settings = [dict(stop_time=1.0 + 0.25 * i, rtol=1e-9, outputs=["*.q"]) for i in range(6)]
    serial = [m.run(**s) for s in settings]
    results = [None] * len(settings)
    errors = []

    def work(i):
        try:
            for _ in range(3):
                results[i] = m.run(**settings[i])
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(settings))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for a, b in zip(serial, results):
        assert np.array_equal(a.time, b.time) and np.array_equal(a.values, b.values)


def test_the_gil_is_released_while_integrating(examples):
    # A run of a few tenths of a second in one thread; the main thread counts meanwhile.
    # Were the GIL held through the integration, the count would stay near zero.
    m = kanesim.load(examples / "chain.mech")
    stop = 0.1
    while True:  # a run long enough to count during (0.1 s at least)
        t0 = time.perf_counter()
        m.run(stop_time=stop)
        if time.perf_counter() - t0 > 0.1 or stop > 1e3:
            break
        stop *= 4
    done = threading.Event()
    seconds = []

    def work():
        t = time.perf_counter()
        m.run(stop_time=stop)
        seconds.append(time.perf_counter() - t)
        done.set()

    count = 0
    th = threading.Thread(target=work)
    th.start()
    while not done.is_set():
        count += 1
        time.sleep(0)
    th.join()
    assert count > 100, f"the main thread ran {count} times during a {seconds[0]:.3f} s run"


def test_ctrl_c_stops_a_long_run(examples):
    # SIGINT's flag raised from a timer (as Ctrl-C does) while a run of several seconds
    # integrates: the run stops within a poll (0.1 s) and raises KeyboardInterrupt.
    import _thread

    m = kanesim.load(examples / "chain.mech", set={"N": 20})
    t0 = time.perf_counter()
    m.run(stop_time=20, interval=0.01)
    full = (time.perf_counter() - t0) * 50  # stop_time=1000 below
    timer = threading.Timer(0.2, _thread.interrupt_main)
    t0 = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            m.run(stop_time=1000, interval=0.01)
    finally:
        timer.cancel()
    elapsed = time.perf_counter() - t0
    assert elapsed < max(0.2 + 1.0, 0.5 * full), (elapsed, full)
