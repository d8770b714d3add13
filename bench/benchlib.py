"""What the benchmarks share: the machine they ran on, free ports, and a check that the machine
stayed quiet while they measured."""

from __future__ import annotations

import os
import platform
import subprocess
import time
from pathlib import Path

from softevo.local_service import free_port  # noqa: F401 - the benches' one free_port


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def redis_version() -> str:
    out = subprocess.run(["redis-server", "--version"], capture_output=True, text=True).stdout
    return next((w[2:] for w in out.split() if w.startswith("v=")), out.strip())


class OtherLoad:
    """CPU used on this machine by processes outside this script's own process tree (other
    users' jobs, steal time), in cores, between `start()` and `stop()`: a check that the machine
    was quiet. This tree is this process and every descendant, with the children they reaped."""

    TICK = os.sysconf("SC_CLK_TCK")

    def __init__(self) -> None:
        self.started = self.busy = self.mine = 0.0

    @classmethod
    def _busy(cls) -> float:
        values = [int(v) for v in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
        return (sum(values) - values[3] - values[4]) / cls.TICK  # all but idle and iowait

    @classmethod
    def _mine(cls) -> float:
        parents, cpu = {}, {}
        for entry in Path("/proc").iterdir():
            if entry.name.isdigit():
                try:
                    fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
                except OSError:
                    continue
                pid = int(entry.name)
                parents[pid] = int(fields[1])
                cpu[pid] = sum(int(v) for v in fields[11:15])  # utime stime cutime cstime
        children: dict[int, list[int]] = {}
        for pid, parent in parents.items():
            children.setdefault(parent, []).append(pid)
        total, todo = 0, [os.getpid()]
        while todo:
            pid = todo.pop()
            total += cpu.get(pid, 0)
            todo += children.get(pid, [])
        return total / cls.TICK

    def start(self) -> OtherLoad:
        self.started, self.busy, self.mine = time.perf_counter(), self._busy(), self._mine()
        return self

    def stop(self) -> float:
        wall = time.perf_counter() - self.started
        other = (self._busy() - self.busy) - (self._mine() - self.mine)
        return max(0.0, other / wall)
