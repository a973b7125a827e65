"""Ctrl-C stops a long fit: the library polls a cancellation flag between chunks."""

from __future__ import annotations

import os
import signal
import threading

import pandas as pd
import pytest

import mrsysid

from conftest import FLIGHT, read_log


def test_sigint_stops_a_fit_and_the_next_fit_runs(quad_x):
    # 30 copies of the 30 s flight end to end (90 030 samples, seconds of work), so the
    # first SIGINT, sent every 20 ms from the start, arrives while the library works.
    one = read_log(FLIGHT)
    span = one["t"].iloc[-1] + 0.01
    long = pd.concat(
        [one.assign(t=one["t"] + k * span) for k in range(30)], ignore_index=True
    )
    stop = threading.Event()
    interrupts = []

    def on_sigint(signum, frame):
        # The first SIGINT raises, as Ctrl-C does; later ones, already on their way
        # when the fit stopped, are counted only.
        interrupts.append(signum)
        if len(interrupts) == 1:
            raise KeyboardInterrupt

    def send():
        while not stop.wait(0.02):
            os.kill(os.getpid(), signal.SIGINT)

    previous = signal.signal(signal.SIGINT, on_sigint)
    sender = threading.Thread(target=send)
    try:
        with pytest.raises(KeyboardInterrupt):
            try:
                sender.start()
                mrsysid.fit(quad_x, samples=long, threads=2)
            finally:
                stop.set()
                sender.join()
        for _ in range(1000):  # let pending handlers run before restoring the default
            pass
    finally:
        signal.signal(signal.SIGINT, previous)
    assert interrupts
    # The interrupted fit's worker has stopped; the library is ready for the next one.
    r = mrsysid.fit(quad_x, samples=one, diagnose=False, threads=2)
    assert r.parameters.loc["C_T0", "estimate"] > 0
