#!/usr/bin/env python3
"""Loads rviz/demo.rviz in RViz on a virtual display (Xvfb) beside a private roscore, takes a
screenshot (xwd) and checks that the 3D view is there and drew something: a large block of
the config's background colour (the render area, not a panel) crossed by grid lines.

    test/rviz_smoke.py OUT_DIR        writes OUT_DIR/rviz_demo.png (and .xwd)

Exit 0 on success; 77 (ctest's SKIP_RETURN_CODE) when RViz, Xvfb or xwd is missing or RViz
cannot start an OpenGL context here; 1 when the view is missing or empty.
"""
import os
import shutil
import struct
import subprocess
import sys
import time
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from ros_processes import free_port, stop  # noqa: E402

CONFIG = os.path.join(HERE, "..", "rviz", "demo.rviz")
SKIP = 77
BACKGROUND = (48, 48, 48)  # Global Options / Background Color in demo.rviz


def free_display():
    for n in range(91, 200):
        if not os.path.exists("/tmp/.X%d-lock" % n) and not os.path.exists("/tmp/.X11-unix/X%d" % n):
            return n
    raise RuntimeError("no free X display number")


def read_xwd(path):
    """Returns (width, height, rows of (r, g, b)) of a 24/32-bit ZPixmap XWD file."""
    data = open(path, "rb").read()
    fields = struct.unpack(">25I", data[:100])
    header_size, _, fmt, depth, width, height = fields[:6]
    byte_order, bits_per_pixel, bytes_per_line = fields[7], fields[11], fields[12]
    red_mask, green_mask, blue_mask, ncolors = fields[14], fields[15], fields[16], fields[19]
    if fmt != 2 or bits_per_pixel not in (24, 32):
        raise ValueError("unsupported XWD format %d / %d bpp" % (fmt, bits_per_pixel))
    step = bits_per_pixel // 8
    offset = header_size + 12 * ncolors
    order = "<" if byte_order == 0 else ">"

    def shift(mask):
        return (mask & -mask).bit_length() - 1

    rs, gs, bs = shift(red_mask), shift(green_mask), shift(blue_mask)
    rows = []
    for y in range(height):
        line = data[offset + y * bytes_per_line: offset + y * bytes_per_line + step * width]
        if step == 4:
            px = struct.unpack(order + "%dI" % width, line)
        else:
            px = [int.from_bytes(line[i:i + 3], "little" if byte_order == 0 else "big") for i in range(0, len(line), 3)]
        rows.append([((p & red_mask) >> rs, (p & green_mask) >> gs, (p & blue_mask) >> bs) for p in px])
    return width, height, rows


def write_png(path, width, height, rows):
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in rows)

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 6)))
        f.write(chunk(b"IEND", b""))


def render_area(width, height, rows):
    """The bounding box of background-coloured pixels and how many there are, and how many
    grid-like pixels (lighter grey, the Grid display) lie inside it."""
    xs, ys, count = [], [], 0
    for y in range(0, height, 2):
        for x in range(0, width, 2):
            if rows[y][x] == BACKGROUND:
                count += 1
                xs.append(x)
                ys.append(y)
    if not xs:
        return None, 0, 0
    box = (min(xs), min(ys), max(xs), max(ys))
    drawn = 0
    for y in range(box[1], box[3] + 1, 2):
        for x in range(box[0], box[2] + 1, 2):
            r, g, b = rows[y][x]
            if (r, g, b) != BACKGROUND and abs(r - g) < 30 and abs(g - b) < 30 and 60 < r < 200:
                drawn += 1
    return box, count, drawn


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out_dir, exist_ok=True)
    for tool in ("rviz", "Xvfb", "xwd", "roscore"):
        if shutil.which(tool) is None:
            print("rviz_smoke: SKIP: %s not installed" % tool)
            return SKIP
    env = dict(os.environ)
    env["ROS_MASTER_URI"] = "http://localhost:%d" % free_port()
    display = free_display()
    env["DISPLAY"] = ":%d" % display
    env["LIBGL_ALWAYS_SOFTWARE"] = "1"
    procs = []
    log = open(os.path.join(out_dir, "rviz_smoke.log"), "w")

    def start(cmd):
        p = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        procs.append(p)
        return p

    try:
        start(["Xvfb", ":%d" % display, "-screen", "0", "1280x900x24", "-nolisten", "tcp"])
        start(["roscore", "-p", env["ROS_MASTER_URI"].rsplit(":", 1)[1]])
        time.sleep(2.0)
        rviz = start(["rviz", "-d", os.path.abspath(CONFIG)])
        xwd = os.path.join(out_dir, "rviz_demo.xwd")
        png = os.path.join(out_dir, "rviz_demo.png")
        deadline = time.time() + 60.0
        result = None
        while time.time() < deadline:
            time.sleep(3.0)
            if rviz.poll() is not None:
                log.flush()
                print("rviz_smoke: SKIP: rviz exited with %d before drawing (see %s)" % (rviz.returncode, log.name))
                return SKIP
            with open(xwd, "wb") as f:
                if subprocess.call(["xwd", "-root", "-silent"], env=env, stdout=f) != 0:
                    continue
            width, height, rows = read_xwd(xwd)
            box, count, drawn = render_area(width, height, rows)
            result = (width, height, rows, box, count, drawn)
            if box and count * 4 > 0.15 * width * height and drawn > 50:
                break
        if result is None:
            print("rviz_smoke: FAIL: no screenshot could be taken")
            return 1
        width, height, rows, box, count, drawn = result
        write_png(png, width, height, rows)
        area = count * 4 / float(width * height)
        print("rviz_smoke: screenshot %s (%dx%d): render area %s, %.0f%% of the screen, %d grid pixels"
              % (png, width, height, box, 100 * area, drawn))
        if box is None or area < 0.15:
            print("rviz_smoke: FAIL: no 3D view (the background colour covers %.1f%% of the screen)" % (100 * area))
            return 1
        if drawn <= 50:
            print("rviz_smoke: FAIL: the 3D view is empty (no grid drawn)")
            return 1
        print("rviz_smoke: OK")
        return 0
    finally:
        for p in reversed(procs):
            stop(p)
        log.close()


if __name__ == "__main__":
    sys.exit(main())
