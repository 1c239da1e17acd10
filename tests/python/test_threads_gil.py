"""Same results for 1 and 2 threads; the GIL is released during long calls."""
import threading
import time

import numpy as np
import pytest

import linesurf


@pytest.fixture
def restore_threads():
    yield
    linesurf.set_threads(0)


def run_all(cloud):
    n = linesurf.normals(cloud)
    h = linesurf.extract_eps_delta(cloud).model
    s = linesurf.extract_shape_approx(cloud, method="hierarchical").model
    img = linesurf.render(h, size=(200, 150))
    return n, h.segments, s.segments, img


def test_one_and_two_threads_identical(restore_threads, igea):
    cloud = linesurf.Model(points=igea.points[::4])
    linesurf.set_threads(1)
    assert linesurf.thread_count() == 1
    one = run_all(cloud)
    linesurf.set_threads(2)
    two = run_all(cloud)
    for a, b in zip(one, two):
        assert np.array_equal(a, b)


def test_render_releases_the_gil(igea):
    model = linesurf.prepare(igea)
    started, done = threading.Event(), threading.Event()

    def work():
        started.set()
        linesurf.render(model, size=(1024, 1024))
        done.set()

    t = threading.Thread(target=work)
    t.start()
    started.wait()
    time.sleep(0.001)
    ticks = 0
    while not done.is_set():
        ticks += 1
    t.join()
    # Holding the GIL, the render would leave this loop no time at all (a few ticks at most).
    assert ticks > 10000, ticks
