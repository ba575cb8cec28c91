"""A test helper, imported by name (tests/conftest.py): signals to a command-line run sent at a
point of its own progress, never after a fixed time."""

import subprocess


def signal_at_first_progress(command: list[str], signum: int) -> tuple[int, str]:
    """Start ``command``, send ``signum`` when it prints its first progress line ("t = ...":
    the simulation is under way, whatever the machine's speed) and return (exit status,
    everything it printed)."""
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True)
    try:
        for line in process.stdout:
            if line.lstrip().startswith("t = "):
                process.send_signal(signum)
                break
        output, _ = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    return process.returncode, output
