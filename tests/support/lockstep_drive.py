"""The simulated drive for the Python script tests: `dyncal drive` on loopback in lockstep (virtual
time: it advances only as fast as the host reads), started and waited for by its ready file."""
import os
import subprocess
import time


def start(dyncal, folder, name, extra=()):
    """Starts a drive whose files are folder/drive_NAME.*; returns (process, its tcp:// URI). Raises
    RuntimeError when it is not ready within 30 s."""
    ready = os.path.join(folder, f"drive_{name}.ready")
    if os.path.exists(ready):
        os.remove(ready)
    p = subprocess.Popen([dyncal, "drive", "--tcp", "127.0.0.1:0", "--lockstep", "--ready-file", ready, "--table",
                          os.path.join(folder, f"drive_{name}.table"), *extra],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(600):
        if os.path.exists(ready) and os.path.getsize(ready) > 0:
            with open(ready) as f:
                return p, f.read().strip()
        if p.poll() is not None:
            break
        time.sleep(0.05)
    p.kill()
    p.wait()
    raise RuntimeError(f"the simulated drive '{name}' did not start")


def stop(p):
    p.kill()
    p.wait()
