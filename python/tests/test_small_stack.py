"""Materials are built in place on the heap: every preset is constructed and
evaluated on a thread whose stack is 64 KiB (the smallest `threading.stack_size`
most platforms accept is 32 KiB)."""

import threading

import numpy as np

import twoscale

STACK = 64 * 1024


def test_every_preset_builds_on_a_64_kib_stack():
    wi = np.array([[0.6, 0.1, 0.8]])
    wo = np.array([[-0.55, -0.05, 0.83]])
    names = twoscale.Material.presets()
    results = {}

    def build():
        for name in names:
            results[name] = twoscale.Material.preset(name).eval(wi, wo)

    previous = threading.stack_size(STACK)
    try:
        thread = threading.Thread(target=build)
        thread.start()
        thread.join()
    finally:
        threading.stack_size(previous)
    assert sorted(results) == sorted(names)
    for name in names:
        # The same values as a model built on the main thread.
        np.testing.assert_array_equal(results[name], twoscale.Material.preset(name).eval(wi, wo))
        assert np.all(results[name] > 0), name
