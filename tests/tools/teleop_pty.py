#!/usr/bin/env python3
"""stride-teleop's keyboard mode on a pseudo-terminal, without any network: LCM writes the
commands to a log file (file://...?mode=w). Keys go in through the pty; the display line, the
terminal's settings (raw while running, restored after every kind of exit) and the logged
commands are checked. Quitting by x, by the Ctrl-C byte and by SIGTERM must each send a stand last.

    teleop_pty.py STRIDE_TELEOP COMMAND_ROBOT
"""
import os
import pty
import select
import signal
import subprocess
import sys
import tempfile
import termios
import time

TELEOP, ROBOT = sys.argv[1], sys.argv[2]


class Session:
    def __init__(self, log, *args):
        self.master, self.slave = pty.openpty()
        self.saved = termios.tcgetattr(self.slave)
        self.output = b""
        self.proc = subprocess.Popen(
            [TELEOP, "--url", f"file://{log}?mode=w", "--rate", "50", *args],
            stdin=self.slave, stdout=self.slave, stderr=self.slave)

    def read(self, timeout):
        ready, _, _ = select.select([self.master], [], [], timeout)
        if ready:
            try:
                self.output += os.read(self.master, 4096)
            except OSError:
                pass

    def wait_for(self, text, timeout=10.0):
        end = time.monotonic() + timeout
        while text.encode() not in self.output:
            if time.monotonic() > end or self.proc.poll() is not None:
                self.read(0.1)
                if text.encode() in self.output:
                    return
                fail(f"no '{text}' in the output:\n{self.output.decode(errors='replace')}")
            self.read(0.05)

    def type(self, keys):
        os.write(self.master, keys)

    def finish(self, timeout=10.0):
        end = time.monotonic() + timeout
        while self.proc.poll() is None:
            if time.monotonic() > end:
                self.proc.kill()
                fail("stride-teleop did not exit")
            self.read(0.05)
        self.read(0.1)
        restored = termios.tcgetattr(self.slave) == self.saved
        os.close(self.master)
        os.close(self.slave)
        return self.proc.returncode, restored


def fail(message):
    print("FAIL:", message)
    sys.exit(1)


def commands(log):
    out = subprocess.run([ROBOT, "dump", log], check=True, capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        utime, vx, vy, yaw, gait, height = line.split()
        rows.append((int(utime), float(vx), float(vy), float(yaw), gait, float(height)))
    return rows


def check_log(log, must_contain):
    rows = commands(log)
    if len(rows) < 5:
        fail(f"{len(rows)} commands logged")
    stamps = [r[0] for r in rows]
    if any(b <= a for a, b in zip(stamps, stamps[1:])):
        fail("command stamps do not increase")
    last = rows[-1]
    if last[1:5] != (0.0, 0.0, 0.0, "stand"):
        fail(f"the last command is not a stand: {last}")
    if not any(abs(r[1] - must_contain[0]) < 1e-9 and abs(r[2] - must_contain[1]) < 1e-9
               and r[4] == must_contain[2] for r in rows):
        fail(f"no command {must_contain} in the log")
    return rows


def main():
    tmp = tempfile.mkdtemp()

    # Keys, the display, raw mode while running, then x.
    log = os.path.join(tmp, "keys.lcmlog")
    s = Session(log)
    s.wait_for("[sent")
    attrs = termios.tcgetattr(s.slave)
    if attrs[3] & (termios.ICANON | termios.ECHO | termios.ISIG):
        fail("the terminal is not in raw mode while stride-teleop runs")
    s.type(b"2www\x1b[Aa")  # trot, vx 0.1 x 3 + the up arrow, vy left 0.05
    s.wait_for("trot  vx +0.40 m/s  vy +0.05 m/s  yaw +0.00 rad/s  height +0.00 m")
    s.type(b"\x1bOD\x1bOD" + b"r")  # left arrow twice (application mode), height up
    s.wait_for("yaw +0.40 rad/s  height +0.01 m")
    time.sleep(1.0)  # the command repeats at --rate 50 while no key comes
    s.type(b"x")
    rc, restored = s.finish()
    if rc != 0 or not restored:
        fail(f"x: exit {rc}, terminal restored: {restored}")
    if b"the last a stand" not in s.output:
        fail("x: no final stand reported")
    rows = check_log(log, (0.4, 0.05, "trot"))
    if not any(abs(r[3] - 0.4) < 1e-9 and abs(r[5] - 0.01) < 1e-9 for r in rows):
        fail("no yaw 0.4 / height 0.01 command logged")
    held = [r for r in rows if abs(r[3] - 0.4) < 1e-9]
    if not 25 <= len(held) <= 150:  # ~50; wide, for a loaded machine
        fail(f"{len(held)} commands in the ~1 s without keys, expected about 50 (--rate 50)")
    print(f"x: {len(rows)} commands, {len(held)} in the ~1 s without keys, terminal restored")

    # The Ctrl-C byte (the terminal is raw: no SIGINT) quits the same way.
    log = os.path.join(tmp, "ctrl_c.lcmlog")
    s = Session(log, "--gaits", "biped")
    s.wait_for("[sent")
    s.type(b"2w4")  # biped: 2 walk, 4 is no gait
    s.wait_for("walk  vx +0.10")
    time.sleep(0.2)
    s.type(b"\x03")
    rc, restored = s.finish()
    if rc != 0 or not restored:
        fail(f"Ctrl-C: exit {rc}, terminal restored: {restored}")
    check_log(log, (0.1, 0.0, "walk"))
    print("Ctrl-C: terminal restored, stand sent")

    # SIGTERM from outside: the loop ends, a stand goes out, the terminal is restored.
    log = os.path.join(tmp, "sigterm.lcmlog")
    s = Session(log)
    s.wait_for("[sent")
    s.type(b"4dd")
    s.wait_for("pace  vx +0.00 m/s  vy -0.10")
    time.sleep(0.2)
    s.proc.send_signal(signal.SIGTERM)
    rc, restored = s.finish()
    if rc != 0 or not restored:
        fail(f"SIGTERM: exit {rc}, terminal restored: {restored}")
    check_log(log, (0.0, -0.1, "pace"))
    print("SIGTERM: terminal restored, stand sent")
    print("PASS: stride-teleop keyboard mode on a pty")


if __name__ == "__main__":
    main()
