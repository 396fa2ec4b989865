"""One Machine shared by several threads gives each thread the results it gets alone.

A pyopencl kernel object holds the arguments of its last launch, so two threads launching the same
kernel on one Machine could each enqueue the other's buffers (measured before the Machine locked its
launches: wrong edge maps in 5 of 10 runs, and segmentation faults). The hammering runs in a
subprocess so that a crash fails this test instead of ending the test run, with Python switching
threads every microsecond so that a launch interrupted between setting arguments and enqueueing is
likely (without the lock: hundreds of wrong results in this run).
"""

import json
import subprocess
import sys
import textwrap

import pytest

import vmcl

HAMMER = textwrap.dedent("""
    import json, sys, threading
    import numpy as np
    sys.setswitchinterval(1e-6)
    import vmcl
    from vmcl import scenes
    from vmcl.cm import reduce, scan
    from vmcl.early.edges import canny
    from vmcl.early.stereo import match

    scene = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    rng = np.random.default_rng(0)
    noise = rng.random((16, 24)).astype(np.float32)
    machine = vmcl.default_machine()

    def operations(k):
        # Each thread runs every operation, in its own order, on inputs of its own.
        image = np.roll(scene.left, k, axis=1)
        ops = [
            ("canny", lambda: canny(image, sigma=1.5)),
            ("stereo", lambda: match(scene.left, scene.right, d_min=0, d_max=8).disparity),
            ("box", lambda: scan.box_sum(noise * (k + 1), 3)),
            ("hist", lambda: reduce.histogram(noise, 16, (0.0, 1.0))),
        ]
        return ops[k % len(ops):] + ops[:k % len(ops)]

    threads, rounds = int(sys.argv[1]), int(sys.argv[2])
    expected = {k: {name: op() for name, op in operations(k)} for k in range(threads)}
    wrong = []

    def worker(k):
        for _ in range(rounds):
            for name, op in operations(k):
                got = op()
                same = np.array_equal(got, expected[k][name], equal_nan=True)
                if not same:
                    wrong.append(f"thread {k}: {name}")

    pool = [threading.Thread(target=worker, args=(k,)) for k in range(threads)]
    for t in pool:
        t.start()
    for t in pool:
        t.join()
    print(json.dumps({"wrong": wrong}))
""")


def test_threads_sharing_the_default_machine_get_their_own_results():
    run = subprocess.run([sys.executable, "-c", HAMMER, "6", "20"], capture_output=True, text=True, timeout=600,
                         check=False)
    if run.returncode < 0 and "NVIDIA" in vmcl.default_machine().device.platform.name:
        # Seen on an H200 (driver 580): a segmentation fault in a worker thread of the driver's library
        # while another thread released an event (no lock of the Machine's covers pyopencl's releases);
        # the cause is not isolated. A Python error (status 1) still fails.
        pytest.xfail(f"killed by signal {-run.returncode} on NVIDIA's OpenCL with threads sharing one Machine "
                     f"(documented: one Machine per thread there): {run.stderr[-500:]}")
    assert run.returncode == 0, f"the hammering process died (status {run.returncode}): {run.stderr[-2000:]}"
    wrong = json.loads(run.stdout.strip().splitlines()[-1])["wrong"]
    assert wrong == [], f"{len(wrong)} results differ from the thread's sequential ones: {wrong[:5]}"
