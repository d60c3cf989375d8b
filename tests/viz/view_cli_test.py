#!/usr/bin/env python3
"""`kanesim view` as a user runs it (talks to 127.0.0.1 only; every step bounded in time):

- --timeout that is not a number of seconds in (0, a week] is a usage error, exit 1, with a
  short message (was: nan served for ever, -5 printed a 309-digit number);
- --html never writes over the model (by its name, a symbolic link or a hard link), nor into
  a FIFO; a page is written whole, with no temporary left beside it;
- while 8 slow clients trickle header lines (the probe's slowloris), a normal request is
  answered within a bound, and a request naming another host (DNS rebinding) gets 403.

usage: view_cli_test.py KANESIM MODEL.mech"""
import hashlib
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

KANESIM, MODEL = sys.argv[1], sys.argv[2]
failures = []


def expect(ok, why):
    if not ok:
        failures.append(why)


def run(args, cwd, timeout=60):
    try:
        return subprocess.run([KANESIM] + args, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        failures.append(f"{args}: still running after {timeout} s")
        return None


def md5(path):
    with open(path, "rb") as f:
        return hashlib.md5(f.read()).hexdigest()


def timeouts(d):
    for value in ["nan", "inf", "-5", "0", "1e9", "-1e308", "abc", "0x10"]:
        p = run(["view", "m.mech", f"--timeout={value}"], d, timeout=20)
        if p is None:
            continue
        out = p.stdout + p.stderr
        expect(p.returncode == 1, f"--timeout {value}: exit {p.returncode}, not 1:\n{out}")
        expect("--timeout" in out, f"--timeout {value}: the message does not name the option:\n{out}")
        expect(not re.search(r"\d{30}", out), f"--timeout {value}: a number of 30 digits or more:\n{out}")
        expect("serving" not in out, f"--timeout {value}: served")


def html_over_model(d):
    before = md5(os.path.join(d, "m.mech"))
    os.symlink("m.mech", os.path.join(d, "link.mech"))
    os.link(os.path.join(d, "m.mech"), os.path.join(d, "hard.mech"))
    for target in ["m.mech", "./m.mech", "link.mech", "hard.mech", os.path.join(d, "m.mech")]:
        p = run(["view", "m.mech", "--html", target, "--stop-time", "0.1"], d)
        if p is None:
            continue
        expect(p.returncode == 1, f"--html {target}: exit {p.returncode}, not 1:\n{p.stderr}")
        expect("would destroy it" in p.stderr, f"--html {target}: no refusal message:\n{p.stderr}")
        expect(md5(os.path.join(d, "m.mech")) == before, f"--html {target}: the model changed")
    os.mkfifo(os.path.join(d, "fifo.html"))
    p = run(["view", "m.mech", "--html", "fifo.html", "--stop-time", "0.1"], d, timeout=30)
    if p is not None:
        expect(p.returncode == 1 and "not a regular file" in p.stderr, f"--html fifo: {p.returncode}\n{p.stderr}")
    for _ in range(2):  # a new page, then over the previous one
        p = run(["view", "m.mech", "--html", "page.html", "--stop-time", "0.1"], d)
        if p is not None:
            expect(p.returncode == 0, f"--html page.html: exit {p.returncode}\n{p.stderr}")
    page = ""
    if os.path.exists(os.path.join(d, "page.html")):
        with open(os.path.join(d, "page.html")) as f:
            page = f.read()
    expect(page.rstrip().endswith("</html>"), "the page is missing or not whole")
    left = [n for n in os.listdir(d) if ".tmp." in n or n.endswith(".part")]
    expect(not left, f"temporaries left beside the page: {left}")


def request(port, host, path="/scene.json", timeout=5):
    t = time.time()
    try:
        s = socket.create_connection(("127.0.0.1", port), timeout=timeout)
        s.sendall(f"GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n".encode())
        data = s.recv(64)
        s.close()
    except OSError as e:
        return f"FAILED ({e})", time.time() - t
    return data.decode(errors="replace"), time.time() - t


def served(d):
    proc = subprocess.Popen([KANESIM, "view", "m.mech", "--stop-time", "0.5", "--timeout", "60"], cwd=d,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        m = re.search(r"http://127\.0\.0\.1:(\d+)/", line)
        expect(m is not None, f"no URL printed: {line!r}")
        if m is None:
            return
        port = int(m.group(1))
        me = f"127.0.0.1:{port}"
        slow, stop = [], threading.Event()
        for _ in range(8):
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.sendall(f"GET / HTTP/1.1\r\nHost: {me}\r\n".encode())
            slow.append(s)

        def trickle():
            while not stop.is_set():
                for s in slow:
                    try:
                        s.sendall(b"X-Slow: y\r\n")
                    except OSError:
                        pass
                stop.wait(0.5)
        t = threading.Thread(target=trickle)
        t.start()
        time.sleep(1.5)
        answer, took = request(port, me)
        expect(answer.startswith("HTTP/1.1 200") and took < 1.5,
               f"during 8 slow clients: {answer[:15]!r} in {took:.2f} s (bound 1.5 s)")
        print(f"normal request during 8 slow clients: {answer[:12]!r} in {took:.3f} s")
        for host in ["evil.example", f"evil.example:{port}", "a"]:
            answer, _ = request(port, host)
            expect(answer.startswith("HTTP/1.1 403"), f"Host {host}: {answer[:15]!r}, not 403")
        stop.set()
        t.join()
        for s in slow:
            s.close()
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def main():
    d = tempfile.mkdtemp(prefix="kanesim_view_cli_")
    shutil.copy(MODEL, os.path.join(d, "m.mech"))
    timeouts(d)
    html_over_model(d)
    shutil.copy(MODEL, os.path.join(d, "m.mech"))  # (in case it was destroyed)
    served(d)
    if failures:
        print("\n".join(failures))
        sys.exit(1)


main()
