"""Process helpers shared by the Python test drivers (readme_runner.py, rviz_smoke.py)."""
import os
import signal
import socket
import subprocess


def free_port():
    """A TCP port on the loopback that nothing listens on now (for a private roscore)."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def stop(proc):
    """Ends a process started with start_new_session=True and everything it started:
    SIGINT first (roslaunch and roscore shut down cleanly), then SIGTERM, then SIGKILL."""
    if proc.poll() is not None:
        return
    for sig, wait in ((signal.SIGINT, 10), (signal.SIGTERM, 5), (signal.SIGKILL, 5)):
        try:
            os.killpg(proc.pid, sig)
            proc.wait(timeout=wait)
            return
        except subprocess.TimeoutExpired:
            continue
        except ProcessLookupError:
            return
