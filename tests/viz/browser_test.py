#!/usr/bin/env python3
"""The viewer page in a real browser: Debian's chromium, headless, WebGL through SwiftShader,
driven over the DevTools protocol (cdp.py).

The page shows tests/viz/circling_scene.h's scene. The poses expected here are that file's
closed forms, computed again below (not read from the page's data), and compared with what
the page reads back from the rendered three.js objects (window.kanesimViewer.bodyPoses: the
world matrices with the display rotation undone).

  offline    --page P --up U   (a) poses at instants and between them, through ?t= and seek;
                               gravity points down on the screen; bodies drawn in their
                               colours where they are; (d) no request leaves the file
  served     --fixture F --up U (b) the same through ServeViewer on 127.0.0.1, any free port;
                               (d) no request leaves the origin
  controls   --page P --up U   (c) the slider, a click on a plot, the arrow keys, play, pause
                               and speed move the time and the plot cursors; hover names;
                               the signal picker
  edge       --page P          a page of corner cases (one instant, a body without a drawing,
                               a signal of NaN only, markup in names) opens without errors
  screenshot --page P --up U --png OUT   (e) a PNG of the page, checked for the bodies' and the
                               cursor's colours where they should be
  nowebgl    --page P --fixture F [--png OUT]   the offline and the served page (up z) in a
                               chromium with WebGL turned off and in one with no GPU and no
                               software fallback, and the served page with three.js blocked: no
                               error box, one line saying why there is no 3-D view, every plot
                               drawn with the closed-form values at every instant, the slider,
                               keys, play and a plot click moving the time and the cursors
  units      --page P          the page of `kanesim view tests/viz/units_plot.mech --html`:
                               every signal's name in the picker and its plot's title carries
                               the unit its quantity has (metres and radians of the joints,
                               the declared and the inferred outputs, joules), and none where
                               the unit is unknown
  events     --page P --csv C  a page from `kanesim view` of a model with events: one tick per
                               event time of the `--events` CSV C of the same run, in order,
                               where the time line puts that time, titled with the element
                               and kind; a click on a tick seeks there; an orange line
                               across the plot at each event
Exit 0 when every check passes; 1 with the failures listed.
"""
import argparse
import contextlib
import math
import os
import pathlib
import struct
import subprocess
import sys
import time
import urllib.request
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cdp  # noqa: E402

# Poses reach the page in single precision and are multiplied in double precision by three.js:
# 2e-6 is ~20 float roundings of numbers up to 1.1. A wrong quaternion order, a wrong
# interpolation or a lost display rotation is off by 1e-2 or more.
POSE_TOL = 2e-6
WIDTH, HEIGHT = 1200, 700
R, OMEGA, H = 0.8, 1.3, 0.3
DT = 1 / 20  # t_k = k / 20, k = 0 … 100
N_TIMES = 101
failures = []


def check(ok, message):
    if not ok:
        failures.append(message)
    return ok


# ---- the closed forms of circling_scene.h --------------------------------------------------

def axes(up):
    """(e1, e2, e_up), right-handed."""
    if up == "y":
        return (0, 0, 1), (1, 0, 0), (0, 1, 0)
    return (1, 0, 0), (0, 1, 0), (0, 0, 1)


def add(*terms):
    return [sum(c * v[i] for c, v in terms) for i in range(3)]


def axis_angle(axis, angle):
    n = math.sqrt(sum(a * a for a in axis))
    s = math.sin(angle / 2) / n
    return (math.cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s)


def qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def rotation(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def pose(name, t, up):
    """(p_WB, q_WB) of a body at t."""
    e1, e2, eu = axes(up)
    if name == "orbiter":
        p = add((R * math.cos(OMEGA * t), e1), (R * math.sin(OMEGA * t), e2), (H, eu))
        return p, axis_angle((1, 2, 3), 2.1 * t)
    p = add((0.9 + 0.2 * math.sin(2 * t), eu))
    return p, qmul(axis_angle(eu, 1.1 * t), axis_angle(e1, 0.6))


def slerp(a, b, s):
    dot = sum(x * y for x, y in zip(a, b))
    if dot < 0:
        b, dot = tuple(-x for x in b), -dot
    theta = math.acos(min(1.0, dot))
    if theta < 1e-12:
        return a
    wa, wb = math.sin((1 - s) * theta) / math.sin(theta), math.sin(s * theta) / math.sin(theta)
    return tuple(wa * x + wb * y for x, y in zip(a, b))


def expected_pose(name, t, up):
    """What the page must show at t: the closed form at an instant; between instants positions
    interpolated linearly and rotations by slerp."""
    k = min(int(math.floor(t / DT + 1e-9)), N_TIMES - 1)
    if abs(t - k * DT) < 1e-12 or k == N_TIMES - 1:
        p, q = pose(name, t, up)
    else:
        s = (t - k * DT) / DT
        (pa, qa), (pb, qb) = pose(name, k * DT, up), pose(name, (k + 1) * DT, up)
        p, q = [a + s * (b - a) for a, b in zip(pa, pb)], slerp(qa, qb, s)
    return p, rotation(q)


def check_poses(page, t, up, where):
    shown = page.evaluate("kanesimViewer.bodyPoses()")
    for name in ("orbiter", "spinner"):
        p, rot = expected_pose(name, t, up)
        got = shown.get(name)
        if not check(got is not None, f"{where}: no body {name} on the page"):
            continue
        dp = max(abs(a - b) for a, b in zip(got["p"], p))
        dr = max(abs(got["R"][i][j] - rot[i][j]) for i in range(3) for j in range(3))
        check(dp <= POSE_TOL, f"{where}: {name} at {got['p']}, expected {p} (off by {dp:.2e})")
        check(dr <= POSE_TOL, f"{where}: {name} rotation {got['R']}, expected {rot} (off by {dr:.2e})")


# A shaded body keeps its hue: its own channel leads the others by a margin (the background
# (233, 237, 242) and the grey grid do not).
def reddish(rgb):
    return rgb[0] > max(rgb[1], rgb[2]) + 50


def bluish(rgb):
    return rgb[2] > max(rgb[0], rgb[1]) + 50


def check_drawing(page, up, where):
    """Gravity points down on the screen: W's up axis, from W's origin, is drawn going up and
    more steeply than either horizontal axis; and each body is drawn in its colour at its
    projected origin."""
    e1, e2, eu = axes(up)
    o, a1, a2, au = (page.evaluate(f"kanesimViewer.screenPoint({list(v)})") for v in ((0, 0, 0), e1, e2, eu))
    rise = o[1] - au[1]  # CSS pixels, y down
    check(rise > 50 and rise > 1.5 * max(abs(o[1] - a1[1]), abs(o[1] - a2[1])),
          f"{where}: W's up axis (up={up}) is drawn from {o} to {au}, horizontal axes to {a1} and {a2}")
    so = page.evaluate("kanesimViewer.screenPosition('orbiter')")
    ss = page.evaluate("kanesimViewer.screenPosition('spinner')")
    if math.dist(so, ss) < 60:
        return  # one may hide the other
    red = page.evaluate(f"kanesimViewer.pixel({so[0]}, {so[1]})")
    blue = page.evaluate(f"kanesimViewer.pixel({ss[0]}, {ss[1]})")
    check(reddish(red), f"{where}: the orbiter (red) is drawn as {red}")
    check(bluish(blue), f"{where}: the spinner (blue) is drawn as {blue}")


def open_page(page, url, what):
    page.navigate(url)
    page.wait_for("window.kanesimViewer && (kanesimViewer.ready || kanesimViewer.failed)", 60, what + " ready")
    errors = page.evaluate("kanesimViewer.errors")
    check(page.evaluate("kanesimViewer.ready") and not errors, f"{what}: the page failed: {errors}")
    return not errors


def check_poses_and_drawing(page, base, up):
    # Opened at an instant and between two (?t= opens paused there).
    for t in (1.25, 1.2625):
        if not open_page(page, f"{base}?t={t}", f"?t={t}"):
            return
        check(page.evaluate("kanesimViewer.time()") == t and not page.evaluate("kanesimViewer.playing()"),
              f"?t={t}: the page is at t={page.evaluate('kanesimViewer.time()')}, not paused at {t}")
        check_poses(page, t, up, f"?t={t}")
        check_drawing(page, up, f"?t={t}")
    # Seeking: instants (the first, the last), between them, and beyond the ends (clamped).
    for t, at in ((0.0, 0.0), (2.5, 2.5), (3.35, 3.35), (4.0375, 4.0375), (0.71, 0.71), (5.0, 5.0),
                  (7.0, 5.0), (-1.0, 0.0)):
        got = page.evaluate(f"kanesimViewer.seek({t})")
        check(abs(got - at) < 1e-12, f"seek({t}) went to {got}, not {at}")
        check_poses(page, at, up, f"seek({t})")
        check_drawing(page, up, f"seek({t})")


def check_requests(page, allowed, where):
    """(d) Every request the page made stayed on the file or the origin."""
    urls = [e["request"]["url"] for e in page.events("Network.requestWillBeSent")]
    check(urls, f"{where}: no request seen (the network events are not working)")
    outside = [u for u in urls if not any(u.startswith(a) for a in allowed)]
    check(not outside, f"{where}: requests outside {allowed}: {outside}")
    problems = [e["entry"]["text"] for e in page.events("Log.entryAdded") if e["entry"]["level"] == "error"]
    problems += [e["exceptionDetails"].get("text", "") for e in page.events("Runtime.exceptionThrown")]
    check(not problems, f"{where}: errors in the console: {problems}")


def run_offline(args):
    url = pathlib.Path(args.page).resolve().as_uri()
    with cdp.Chromium(args.chromium, WIDTH, HEIGHT) as browser:
        page = browser.new_page(WIDTH, HEIGHT)
        check_poses_and_drawing(page, url, args.up)
        check_requests(page, [url, "data:", "blob:"], "offline page")


@contextlib.contextmanager
def fixture_server(args, up):
    """The fixture's viewer server: yields its URL (None when it printed none, already
    reported), and at the end asks it to quit and checks that it exits with 0."""
    server = subprocess.Popen([args.fixture, "serve", up], stdout=subprocess.PIPE, text=True)
    try:
        url = server.stdout.readline().strip()
        if not check(url.startswith("http://127.0.0.1:"), f"the server printed {url!r}, not its URL"):
            yield None
            return
        yield url
        with urllib.request.urlopen(url + "quit", timeout=10) as reply:
            check(reply.status == 200, f"GET /quit answered {reply.status}")
        check(server.wait(timeout=10) == 0, f"the server exited with {server.returncode}")
    finally:
        if server.poll() is None:
            server.kill()
            server.wait()


def run_served(args):
    with fixture_server(args, args.up) as url:
        if url is None:
            return
        with cdp.Chromium(args.chromium, WIDTH, HEIGHT) as browser:
            page = browser.new_page(WIDTH, HEIGHT)
            check_poses_and_drawing(page, url, args.up)
            check_requests(page, [url, "data:", "blob:"], "served page")
            urls = {e["request"]["url"] for e in page.events("Network.requestWillBeSent")}
            check(url + "scene.json" in urls and url + "lib/three.min.js" in urls,
                  f"the served page did not load its scene and libraries from the server: {sorted(urls)}")


def cursor_check(page, t, where, tol):
    """Every plot's cursor is at t, as a time and as a place on the plot."""
    times = page.evaluate("kanesimViewer.cursorTimes()")
    check(times, f"{where}: no plot cursors")
    for name, at in times.items():
        check(at is not None and abs(at - t) <= tol, f"{where}: the cursor of {name} is at {at}, not {t}")
        left = page.evaluate(f"document.querySelector('.plot[data-signal=\"{name}\"] .plot-cursor')"
                             ".getBoundingClientRect().left")
        x = page.evaluate(f"kanesimViewer.plotPoint('{name}', {t})[0]")
        check(abs(left - x) <= 1.0, f"{where}: the cursor of {name} is drawn at x={left}, the plot has t={t} at {x}")


def wait_frames(page, n=3):
    page.evaluate(f"new Promise(r => {{ let k = {n}; const f = () => (--k > 0 ? requestAnimationFrame(f) : r(1)); "
                  "requestAnimationFrame(f); })")


def run_controls(args):
    url = pathlib.Path(args.page).resolve().as_uri()
    with cdp.Chromium(args.chromium, WIDTH, HEIGHT) as browser:
        page = browser.new_page(WIDTH, HEIGHT)
        if not open_page(page, url + "?t=0", "controls"):
            return
        plotted = page.evaluate("kanesimViewer.plotted()")
        check(plotted == ["orbiter.x", "spinner.height", "energy"], f"default plots: {plotted}")
        # Scrubbing: the slider, as a user's input event.
        page.evaluate("(() => { const s = document.getElementById('slider'); s.value = 2; "
                      "s.dispatchEvent(new Event('input', {bubbles: true})); })()")
        check(page.evaluate("kanesimViewer.time()") == 2, f"slider: time {page.evaluate('kanesimViewer.time()')}")
        check_poses(page, 2.0, args.up, "slider at 2")
        cursor_check(page, 2.0, "slider at 2", 1e-3)
        # A click on a plot seeks there (to within a pixel).
        area_w = page.evaluate("document.querySelector('.plot-graph').getBoundingClientRect().width")
        x, y = page.evaluate("kanesimViewer.plotPoint('energy', 3.3)")
        page.click(x, y)
        t = page.evaluate("kanesimViewer.time()")
        check(abs(t - 3.3) <= 2 * 5.0 / area_w, f"a click on the energy plot at t=3.3 went to {t}")
        check(not page.evaluate("kanesimViewer.playing()"), "a click on a plot should pause")
        cursor_check(page, t, "after the plot click", 1e-3)
        check_poses(page, t, args.up, "after the plot click")
        # The arrow keys step one written instant.
        page.evaluate("kanesimViewer.seek(3.3)")
        page.key("ArrowRight", "ArrowRight", 39)
        check(page.evaluate("kanesimViewer.time()") == 67 / 20, f"→ from 3.3: {page.evaluate('kanesimViewer.time()')}")
        page.key("ArrowLeft", "ArrowLeft", 37)
        page.key("ArrowLeft", "ArrowLeft", 37)
        check(page.evaluate("kanesimViewer.time()") == 65 / 20, f"←← from 3.35: {page.evaluate('kanesimViewer.time()')}")
        # Play at 4× for a second of the page's own clock, then pause.
        page.evaluate("kanesimViewer.seek(0)")
        page.evaluate("(() => { const s = document.getElementById('speed'); s.value = '4'; "
                      "s.dispatchEvent(new Event('change')); })()")
        bx, by = page.evaluate("(() => { const r = document.getElementById('play').getBoundingClientRect(); "
                               "return [r.left + r.width / 2, r.top + r.height / 2]; })()")
        page.click(bx, by)
        # The page advances its time once a frame by (frame timestamp - last one) x speed and
        # loops at the end; read its time and the timestamp of its last advance together, twice,
        # and compare the advance with 4 x the clock's, modulo the loop's length: exact however
        # slow the frames and late the timers of a loaded machine (which may loop past the end).
        # The first read waits for the first advance after play (clock() is null until then: a
        # loaded machine's first frame can come later than 200 ms; 2 = no frame within 10 s).
        rate_error = page.evaluate(
            "(async () => { const s = document.getElementById('slider'), T = s.max - s.min; "
            "const read = () => [kanesimViewer.time(), kanesimViewer.clock()]; "
            "await new Promise(r => setTimeout(r, 200)); "
            "for (let i = 0; i < 500 && kanesimViewer.clock() === null; ++i) await new Promise(r => setTimeout(r, 20)); "
            "const [t0, c0] = read(); if (c0 === null) return 2; "
            "await new Promise(r => setTimeout(r, 500)); const [t1, c1] = read(); "
            "if (!(c1 > c0)) return 1; const r = (((t1 - t0) - 4 * (c1 - c0) / 1000) % T + T) % T; "
            "return Math.min(r, T - r); })()")
        check(page.evaluate("kanesimViewer.playing()"), "the play button did not start playing")
        check(rate_error < 1e-6, f"playing at 4x: the time is {rate_error:.3g} s off 4 x the page's frame clock")
        page.click(bx, by)
        t1 = page.evaluate("kanesimViewer.time()")
        wait_frames(page, 5)
        check(not page.evaluate("kanesimViewer.playing()") and page.evaluate("kanesimViewer.time()") == t1,
              "the pause button did not stop the time")
        cursor_check(page, t1, "after pause", 1e-3)
        # Hover: the body's name (and label) under the mouse; nothing over the background.
        sx, sy = page.evaluate("kanesimViewer.screenPosition('spinner')")
        page.mouse("mouseMoved", sx, sy)
        wait_frames(page)
        text = page.evaluate("kanesimViewer.hoverText()")
        check(text == "spinner\nCylinder r 0.1 m", f"hovering the spinner shows {text!r}")
        vx, vy = page.evaluate("(() => { const r = document.querySelector('#view canvas').getBoundingClientRect(); "
                               "return [r.left + 5, r.top + 5]; })()")
        page.mouse("mouseMoved", vx, vy)
        wait_frames(page)
        check(page.evaluate("kanesimViewer.hoverText()") == "", "hovering the background shows a name")
        # The signal picker: hide one plot, show another (its cursor at the current time).
        for name in ("energy", "orbiter.angle"):
            cx, cy = page.evaluate(f"(() => {{ const r = document.querySelector('#signal-list input[data-signal=\"{name}\"]')"
                                   ".getBoundingClientRect(); return [r.left + r.width / 2, r.top + r.height / 2]; })()")
            page.click(cx, cy)
        plotted = page.evaluate("kanesimViewer.plotted()")
        check(plotted == ["orbiter.x", "spinner.height", "orbiter.angle"], f"after the picker: {plotted}")
        cursor_check(page, t1, "new plot", 1e-3)
        check(not page.evaluate("kanesimViewer.errors"), f"errors: {page.evaluate('kanesimViewer.errors')}")


def run_edge(args):
    url = pathlib.Path(args.page).resolve().as_uri()
    with cdp.Chromium(args.chromium, WIDTH, HEIGHT) as browser:
        page = browser.new_page(WIDTH, HEIGHT)
        if not open_page(page, url, "edge"):
            return
        check(page.evaluate("kanesimViewer.time()") == 2.0, "edge: not at its one instant")
        check(page.evaluate("kanesimViewer.seek(5)") == 2.0, "edge: seeking past the one instant")
        check(page.evaluate("document.getElementById('slider').disabled"), "edge: the slider should be disabled")
        shown = page.evaluate("kanesimViewer.bodyPoses()")
        check(sorted(shown) == ["</script><b>x", "frame"], f"edge: bodies {sorted(shown)}")
        frame = shown.get("frame", {"p": None, "R": None})
        check(frame["p"] and max(abs(a - b) for a, b in zip(frame["p"], (1, 2, 3))) < POSE_TOL,
              f"edge: frame at {frame['p']}")
        quarter = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
        check(frame["R"] and max(abs(frame["R"][i][j] - quarter[i][j]) for i in range(3) for j in range(3)) < POSE_TOL,
              f"edge: frame turned {frame['R']}")
        check(page.evaluate("document.title") == "edge <cases>", "edge: title")
        check(page.evaluate("kanesimViewer.plotted()") == ["gap", "<i>one</i>"], "edge: plots")
        check(page.evaluate("document.querySelectorAll('#signal-list i, #plots i, #tooltip b').length") == 0,
              "edge: markup in a name became elements")
        # Up is −x: W's −x axis is drawn going up the screen.
        o, a = page.evaluate("kanesimViewer.screenPoint([0, 0, 0])"), page.evaluate("kanesimViewer.screenPoint([-1, 0, 0])")
        check(o[1] - a[1] > 50, f"edge: up (−x) is drawn from {o} to {a}")
        sx, sy = page.evaluate("kanesimViewer.screenPosition('</script><b>x')")
        page.mouse("mouseMoved", sx, sy)
        wait_frames(page)
        text = page.evaluate("kanesimViewer.hoverText()")
        check(text == "</script><b>x\n<label>", f"edge: hovering the box shows {text!r}")
        check(not page.evaluate("kanesimViewer.errors"), f"edge: errors {page.evaluate('kanesimViewer.errors')}")
        check_requests(page, [url, "data:", "blob:"], "edge page")


def decode_png(data):
    """RGB(A) 8-bit, non-interlaced PNG → (width, height, channels, rows of bytes)."""
    check(data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG")
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour in (2, 6) and interlace == 0, (depth, colour, interlace)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    channels = 4 if colour == 6 else 3
    raw, stride, rows, prev = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = prev[i], prev[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return width, height, channels, rows


def run_screenshot(args):
    url = pathlib.Path(args.page).resolve().as_uri()
    width, height = 1000, 560
    with cdp.Chromium(args.chromium, width, height) as browser:
        page = browser.new_page(width, height)
        if not open_page(page, url + "?t=2.1", "screenshot"):
            return
        wait_frames(page)
        so = page.evaluate("kanesimViewer.screenPosition('orbiter')")
        ss = page.evaluate("kanesimViewer.screenPosition('spinner')")
        cursor = page.evaluate("(() => { const r = document.querySelector('.plot[data-signal=\"orbiter.x\"] .plot-cursor')"
                               ".getBoundingClientRect(); return [r.left, r.top, r.bottom]; })()")
        png = page.screenshot()
    pathlib.Path(args.png).write_bytes(png)
    w, h, ch, rows = decode_png(png)
    check((w, h) == (width, height), f"the screenshot is {w}x{h}, not {width}x{height}")
    pixel = lambda x, y: tuple(rows[int(y)][int(x) * ch:int(x) * ch + 3])  # noqa: E731
    red, blue = pixel(*so), pixel(*ss)
    check(reddish(red), f"screenshot: the orbiter's pixel is {red}, not red")
    check(bluish(blue), f"screenshot: the spinner's pixel is {blue}, not blue")
    column = [pixel(cursor[0] + 1, y) for y in range(int(cursor[1]) + 2, int(cursor[2]) - 2)]
    reds = sum(1 for p in column if p[0] > 180 and p[1] < 110 and p[2] < 110)
    check(reds > 0.8 * len(column), f"screenshot: the orbiter.x plot's cursor column is red in {reds} of {len(column)} px")
    print(f"screenshot: {args.png}, {len(png)} bytes")


# ---- without WebGL ---------------------------------------------------------------------------

# The signals the page plots at first, in closed form (circling_scene.cpp); they reach the page
# as float32: 1e-6 is ~10 roundings of values up to 1.5. A plot of the wrong signal, or with
# instants dropped or shifted, is off by 1e-2 or more.
SIGNALS = {
    "orbiter.x": lambda t: R * math.cos(OMEGA * t),
    "spinner.height": lambda t: 0.9 + 0.2 * math.sin(2 * t),
    "energy": lambda t: 1 + 0.5 * math.sin(OMEGA * t) ** 2,
}
SIGNAL_TOL = 1e-6
WEBGL_PROBE = ("(() => { const c = () => document.createElement('canvas'); "
               "return !!(c().getContext('webgl') || c().getContext('webgl2') || c().getContext('experimental-webgl')); })()")


def check_plots_drawn(page, where):
    """Each default plot holds the closed form at every instant and has drawn its line."""
    plotted = page.evaluate("kanesimViewer.plotted()")
    check(plotted == list(SIGNALS), f"{where}: plots {plotted}")
    for name, value in SIGNALS.items():
        rows = page.evaluate(f"kanesimViewer.plotRows('{name}')") or []
        if not check(len(rows) == N_TIMES, f"{where}: {name} has {len(rows)} points, not {N_TIMES}"):
            continue
        dt = max(abs(t - k * DT) for k, (t, _) in enumerate(rows))
        dv = max(abs(v - value(k * DT)) if v is not None else math.inf for k, (_, v) in enumerate(rows))
        check(dt < 1e-12 and dv < SIGNAL_TOL, f"{where}: {name} is off its closed form by {dv:.2e} (times by {dt:.2e})")
        # Drawn: pixels of the line's colour (#1f5fa8, anti-aliased) on the plot's canvases, at
        # least one per column of half the plot's width (a 101-point line crosses all of it).
        blue, width = page.evaluate(
            f"(() => {{ const area = document.querySelector('.plot[data-signal=\"{name}\"] .plot-graph'); let n = 0; "
            "for (const c of area.querySelectorAll('canvas')) { const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; "
            "for (let i = 0; i < d.length; i += 4) if (d[i + 3] > 128 && d[i + 2] > d[i] + 60 && d[i + 2] > d[i + 1] + 30) ++n; } "
            "return [n, area.getBoundingClientRect().width]; })()")
        check(blue > width / 2, f"{where}: the {name} plot drew {blue} line pixels over {width} px")


def check_without_webgl(page, url, where, reason):
    """The page without a 3-D view: no error box, the one line, and the plots and time line working."""
    if not open_page(page, url + "?t=0", where):
        return
    box = page.evaluate("(() => { const m = document.getElementById('message'); return m.hidden ? '' : m.textContent; })()")
    check(box == "", f"{where}: an error box: {box!r}")
    line = page.evaluate("kanesimViewer.noView3d")
    check(line.startswith("No 3-D view: ") and reason in line and line.endswith("the plots and the time line work."),
          f"{where}: the line is {line!r}, expected one naming {reason!r}")
    shown, height = page.evaluate("(() => { const n = document.getElementById('note'); "
                                  "return [n.hidden ? '' : n.innerText, n.getBoundingClientRect().height]; })()")
    lines = page.evaluate("parseFloat(getComputedStyle(document.getElementById('note')).lineHeight) || 18")
    # One sentence, shown as text; it may wrap once where the 3-D panel is narrower than it.
    check(shown == line and 0 < height < 2.5 * lines, f"{where}: the note shows {shown!r} in {height} px ({lines} a line)")
    check(page.evaluate("document.querySelectorAll('#view canvas').length") == 0, f"{where}: a 3-D canvas without WebGL")
    check(page.evaluate("kanesimViewer.bodyPoses()") is None, f"{where}: body poses without a 3-D view")
    check_plots_drawn(page, where)
    cursor_check(page, 0.0, f"{where}, opened at 0", 1e-3)
    for t in (2.0, 4.35):  # the slider, as a user's input event
        page.evaluate(f"(() => {{ const s = document.getElementById('slider'); s.value = {t}; "
                      "s.dispatchEvent(new Event('input', {bubbles: true})); })()")
        check(page.evaluate("kanesimViewer.time()") == t, f"{where}: slider to {t}: time {page.evaluate('kanesimViewer.time()')}")
        cursor_check(page, t, f"{where}, slider at {t}", 1e-3)
    page.key("ArrowRight", "ArrowRight", 39)  # the next written instant
    check(page.evaluate("kanesimViewer.time()") == 88 / 20, f"{where}: → from 4.35: {page.evaluate('kanesimViewer.time()')}")
    x, y = page.evaluate("kanesimViewer.plotPoint('energy', 1.5)")
    page.click(x, y)
    area_w = page.evaluate("document.querySelector('.plot-graph').getBoundingClientRect().width")
    t = page.evaluate("kanesimViewer.time()")
    check(abs(t - 1.5) <= 2 * 5.0 / area_w, f"{where}: a click on the energy plot at t=1.5 went to {t}")
    cursor_check(page, t, f"{where}, after the plot click", 1e-3)
    bx, by = page.evaluate("(() => { const r = document.getElementById('play').getBoundingClientRect(); "
                           "return [r.left + r.width / 2, r.top + r.height / 2]; })()")
    page.click(bx, by)
    try:
        page.wait_for(f"kanesimViewer.time() > {t} + 0.1", 20, f"{where}: the time to advance while playing")
    except cdp.ProtocolError as e:
        failures.append(str(e))
    page.click(bx, by)
    t1 = page.evaluate("kanesimViewer.time()")
    wait_frames(page, 5)
    check(not page.evaluate("kanesimViewer.playing()") and page.evaluate("kanesimViewer.time()") == t1,
          f"{where}: the pause button did not stop the time")
    cursor_check(page, t1, f"{where}, after play and pause", 1e-3)
    check(not page.evaluate("kanesimViewer.errors"), f"{where}: errors {page.evaluate('kanesimViewer.errors')}")


def run_nowebgl(args):
    offline = pathlib.Path(args.page).resolve().as_uri()
    with fixture_server(args, "z") as served:
        if served is None:
            return
        # Chromium's reasons (webglcontextcreationerror), as the line shows them.
        for mode, reason in (("disabled", "disabled by enterprise policy or commandline switch"),
                             ("no-gpu", "Could not create a WebGL context")):
            with cdp.Chromium(args.chromium, WIDTH, HEIGHT, webgl=mode) as browser:
                page = browser.new_page(WIDTH, HEIGHT)
                page.navigate("about:blank")
                if not check(not page.evaluate(WEBGL_PROBE), f"{mode}: this chromium has WebGL; the test means nothing"):
                    continue
                check_without_webgl(page, offline, f"offline page, WebGL {mode}", f"this browser has no WebGL ({reason})")
                check_requests(page, [offline, "data:", "blob:"], f"offline page, WebGL {mode}")
                page = browser.new_page(WIDTH, HEIGHT)
                check_without_webgl(page, served, f"served page, WebGL {mode}", f"this browser has no WebGL ({reason})")
                if mode == "no-gpu" and args.png and page.evaluate("kanesimViewer.ready"):
                    page.evaluate("kanesimViewer.seek(2.1)")
                    wait_frames(page)
                    pathlib.Path(args.png).write_bytes(page.screenshot())
                    print(f"screenshot: {args.png}")
        # WebGL works but three.js does not load (served, its file blocked): the same degradation.
        with cdp.Chromium(args.chromium, WIDTH, HEIGHT) as browser:
            page = browser.new_page(WIDTH, HEIGHT)
            page.send("Network.setBlockedURLs", {"urls": ["*/lib/three.min.js"]})
            check_without_webgl(page, served, "served page, three.js blocked", "three.js did not load (libjs-three)")


# units_plot.mech's signals and the units of what they measure (the physics, not the model's
# text): the prismatic joint's displacement and speed, the hinge's angle and rate, a force, a
# height, the energies, twice a rate; `scaled` (a parameter of no unit times a rate) has no
# unit the check can know.
UNITS_PLOT = {"slider.q": "m", "slider.u": "m/s", "hinge.q": "rad", "hinge.u": "rad/s", "spring_force": "N",
              "tip_height": "m", "doubled": "rad/s", "scaled": "", "kinetic_energy": "J", "potential_energy": "J"}


def run_units(args):
    url = pathlib.Path(args.page).resolve().as_uri()
    with cdp.Chromium(args.chromium, WIDTH, HEIGHT) as browser:
        page = browser.new_page(WIDTH, HEIGHT)
        if not open_page(page, url, "units page"):
            return
        labels = page.evaluate("Array.from(document.querySelectorAll('#signal-list label')).map((l) => "
                               "[l.querySelector('input').dataset.signal, l.textContent.trim()])")
        labels = dict(labels or [])
        for name, unit in UNITS_PLOT.items():
            want = name + (f" [{unit}]" if unit else "")
            check(labels.get(name) == want, f"picker: {name} reads {labels.get(name)!r}, not {want!r}")
            # Plotted (a click on its box when it is not yet): the plot's title carries the unit.
            page.evaluate(f"(() => {{ const b = document.querySelector('#signal-list input[data-signal=\"{name}\"]'); "
                          "if (b && !b.checked) b.click(); })()")
            title = page.evaluate(f"(() => {{ const t = document.querySelector('.plot[data-signal=\"{name}\"] .plot-title'); "
                                  "return t ? t.textContent : null; })()")
            check(title == want, f"plot: {name}'s title reads {title!r}, not {want!r}")
        check_requests(page, [url, "data:", "blob:"], "units page")


# Of 17 rows of the plot canvas across the middle of plot %s (3 px apart), how many have an
# orange pixel (red above green above blue, by 30) within a pixel of time %r's x plus %d px.
EVENT_LINE_ROWS = """((name, t, dx) => {
  const p = kanesimViewer.plotPoint(name, t);
  if (!p) return null;
  let rows = 0;
  for (const c of document.querySelectorAll('.plot-graph canvas')) {
    const r = c.getBoundingClientRect();
    if (p[0] < r.left || p[0] > r.right || p[1] < r.top || p[1] > r.bottom) continue;
    const sx = c.width / r.width, sy = c.height / r.height, ctx = c.getContext('2d');
    for (let k = -8; k <= 8; ++k) {
      const x = Math.round((p[0] + dx - r.left) * sx), y = Math.round((p[1] + 3 * k - r.top) * sy);
      const d = ctx.getImageData(x - 1, y, 3, 1).data;
      for (let i = 0; i < 12; i += 4)
        if (d[i] > d[i + 1] + 30 && d[i + 1] > d[i + 2] + 30) { ++rows; break; }
    }
  }
  return rows;
})(%s, %r, %d)"""


def run_events(args):
    import csv
    with open(args.csv, newline="") as f:
        rows = list(csv.DictReader(f))
    times = sorted({float(r["time"]) for r in rows})
    check(len(times) >= 3, f"events: the log {args.csv} has {len(times)} event times (the model should bounce)")
    url = pathlib.Path(args.page).resolve().as_uri() + "?play=0"
    with cdp.Chromium(args.chromium, WIDTH, HEIGHT) as browser:
        page = browser.new_page(WIDTH, HEIGHT)
        if not open_page(page, url, "events"):
            return
        marks = page.evaluate("kanesimViewer.eventMarks()")
        got = [m["t"] for m in marks]
        check(got == times, f"events: the time line marks {got}, the events log has {times}")
        t0, t1 = page.evaluate("kanesimViewer.seek(-1e9)"), page.evaluate("kanesimViewer.seek(1e9)")
        left, right, top, bottom = page.evaluate(
            "(() => { const r = document.getElementById('slider').getBoundingClientRect();"
            " return [r.left, r.right, r.top, r.bottom]; })()")
        for m in marks:
            # The strip is the slider's track: its box less 8 px a side (the thumb's half width).
            x = left + 8 + (m["t"] - t0) / (t1 - t0) * (right - left - 16)
            check(abs(m["x"] - x) <= 1.5, f"events: the tick of t={m['t']} is at x={m['x']:.1f}, the track puts it at {x:.1f}")
            check(top - 6 <= m["y"] <= bottom, f"events: the tick of t={m['t']} is at y={m['y']}, not on the slider")
        for r in rows:
            title = next((m["title"] for m in marks if m["t"] == float(r["time"])), "")
            check(r["element"] in title and r["kind"] in title,
                  f"events: the tick of t={r['time']} says {title!r}, not {r['element']}: {r['kind']}")
        # Each event is a thin orange line across the plots: orange pixels from the plot's top
        # to its bottom at the event's x, none 5 px beside it (where no other event is near).
        name = page.evaluate("kanesimViewer.plotted()")[0]
        t_px = (t1 - t0) / max(1.0, page.evaluate(f"kanesimViewer.plotPoint({name!r}, {t1})[0]")
                               - page.evaluate(f"kanesimViewer.plotPoint({name!r}, {t0})[0]"))
        for t in times:
            if min([abs(t - u) for u in times if u != t] or [1e9]) < 12 * t_px:
                continue
            on, beside = (page.evaluate(EVENT_LINE_ROWS % (repr(name), t, dx)) for dx in (0, 5))
            check(on is not None and on >= 14, f"events: the plot {name} has an orange line at t={t} in {on} of 17 rows")
            check(beside == 0, f"events: the plot {name} is orange 5 px beside the event at t={t} in {beside} rows")
        for m in marks[:3]:
            page.click(m["x"], m["y"])
            wait_frames(page)
            check(page.evaluate("kanesimViewer.time()") == m["t"],
                  f"events: a click on the tick of t={m['t']} went to {page.evaluate('kanesimViewer.time()')}")
            check(not page.evaluate("kanesimViewer.playing()"), "events: a click on a tick should pause")
        check_requests(page, [url.split("?")[0], "data:", "blob:"], "events page")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("case", choices=["offline", "served", "controls", "edge", "screenshot", "nowebgl", "units", "events"])
    parser.add_argument("--chromium", default="chromium")
    parser.add_argument("--page")
    parser.add_argument("--fixture")
    parser.add_argument("--up", choices=["z", "y"], default="z")
    parser.add_argument("--png")
    parser.add_argument("--csv")
    args = parser.parse_args()
    start = time.monotonic()
    try:
        {"offline": run_offline, "served": run_served, "controls": run_controls, "edge": run_edge,
         "screenshot": run_screenshot, "nowebgl": run_nowebgl, "units": run_units, "events": run_events}[args.case](args)
    except cdp.ProtocolError as e:
        failures.append(f"browser: {e}")
    for f in failures:
        print("FAIL:", f)
    print(f"{args.case} (up {args.up}): {'FAILED' if failures else 'passed'} in {time.monotonic() - start:.1f} s")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
