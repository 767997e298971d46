"""An I++ DME session against `trueaxis serve` from Python's standard library alone.

This is the smallest client measuring software needs: a TCP socket, lines ending in CR LF, a tag
per command, and reading until that tag's transaction is complete (`%`). It probes a point on
the virtual CMM and scans a circle, and checks what comes back against the geometry asked for.
"""
import math
import os
import re
import socket
import subprocess

import pytest

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")  # ctest sets it; else the installed CLI


class IppSession:
    def __init__(self, port):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=30)
        self.buf = b""
        self.tag = 0

    def line(self):
        while b"\r\n" not in self.buf:
            chunk = self.sock.recv(65536)
            if not chunk:
                raise ConnectionError("the server closed the connection")
            self.buf += chunk
        line, self.buf = self.buf.split(b"\r\n", 1)
        return line.decode("ascii")

    def call(self, command):
        """Sends a command with a new tag; returns its data lines and error lines."""
        self.tag += 1
        tag = f"{self.tag:05d}"
        self.sock.sendall(f"{tag} {command}\r\n".encode("ascii"))
        data, errors = [], []
        while True:
            line = self.line()
            if not line.startswith(tag):
                continue  # events (E0000, daemons)
            kind = line[6]
            if kind == "#":
                data.append(line[8:])
            elif kind == "!":
                errors.append(line[8:])
            elif kind == "%":
                return data, errors


def test_a_python_client_probes_and_scans_the_virtual_cmm():
    server = subprocess.Popen(
        [TRUEAXIS, "serve", "--port", "0", "--time-scale", "0", "--sessions", "1"],
        stdout=subprocess.PIPE, text=True)
    try:
        port = int(re.search(r"127\.0\.0\.1:(\d+)", server.stdout.readline()).group(1))
        s = IppSession(port)
        assert s.call("StartSession()") == ([], [])
        s.call("Home()")
        s.call("OnPtMeasReport(X(), Y(), Z(), IJK())")
        # Without a part, a probing meets the plane through its point square to its direction.
        data, errors = s.call("PtMeas(X(10), Y(20), Z(-30), IJK(0, 0, 1))")
        assert errors == []
        values = [float(v) for v in re.findall(r"-?\d+\.\d+", data[0])]
        assert values[:3] == pytest.approx([10, 20, -30], abs=1e-4)
        assert values[3:] == pytest.approx([0, 0, 1], abs=1e-6)
        # A scan streams bare numbers, in the order OnScanReport sets.
        s.call("OnScanReport(X(), Y(), Z())")
        data, errors = s.call("ScanOnCircle(0, 0, -50, 25, 0, -50, 0, 0, 1, 180, 0, 2)")
        assert errors == []
        numbers = [float(v) for line in data for v in line.split(",")]
        points = [numbers[i:i + 3] for i in range(0, len(numbers), 3)]
        assert 85 <= len(points) <= 95
        for x, y, z in points:
            assert math.hypot(x, y) == pytest.approx(25, abs=1e-5)  # 5-decimal round-off
        # Out of the travel: the specification's error 2500, then nothing until ClearAllErrors.
        data, errors = s.call("GoTo(X(100000))")
        assert "2500" in errors[0]
        assert "0514" in s.call("Get(X())")[1][0]
        s.call("ClearAllErrors()")
        assert s.call("Get(X())")[1] == []
        s.call("EndSession()")
        s.sock.close()
        assert server.wait(timeout=30) == 0
    finally:
        if server.poll() is None:
            server.kill()
