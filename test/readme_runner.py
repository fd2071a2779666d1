#!/usr/bin/env python3
"""Runs the runnable command blocks of the README and of the docs it continues into
(docs/QUICKSTART.md, docs/TOOLS.md) and checks what they print, so they cannot drift from what
works.

A block is runnable when the line before its opening fence is a marker comment:

    <!-- readme-run: OPTION ... -->

Options (space-separated; values with spaces in double quotes):
  setup          run first-class: the environment it leaves (e.g. `source devel/setup.bash`)
                 is the environment of every later block
  background     start it and leave it running (a node) until the end of the run
  wait=NAME      background: wait until NAME is an advertised topic or service
  expect=REGEX   the output (stdout and stderr) must match; may be given several times
  exit=N|any     the exit status it must end with (default 0)
  timeout=S      seconds before it counts as hung (default 60)

Every block runs with bash from the repository's root, against a private roscore on a free
port (the README's `roscore` is not needed), with ROS_HOME inside the build folder. The run
stops at the first failure and prints the block, its output and what was wrong.

Several files run as one session, in the order given and each file's blocks in order: one
roscore, the environment of a `setup` block and the `background` processes carry over to the
later files (docs/QUICKSTART.md continues the README's quick start: its blocks use the node
the README starts). Without a file: README.md, docs/QUICKSTART.md, docs/TOOLS.md.

    test/readme_runner.py [FILE...] [--keep-going] [--list]
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ros_processes import free_port, stop  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_FILES = ["README.md", "docs/QUICKSTART.md", "docs/TOOLS.md"]
MARKER = re.compile(r"^<!--\s*readme-run:?(.*?)-->\s*$")


class Block:
    def __init__(self, path, line, text, options):
        self.path = path
        self.line = line
        self.text = text
        self.options = options

    def get(self, name, default=None):
        values = [v for k, v in self.options if k == name]
        return values[-1] if values else default

    def all(self, name):
        return [v for k, v in self.options if k == name]

    def has(self, name):
        return any(k == name for k, _ in self.options)


def parse(readme):
    blocks = []
    lines = open(readme, encoding="utf-8").read().splitlines()
    i = 0
    while i < len(lines):
        m = MARKER.match(lines[i].strip())
        if m and i + 1 < len(lines) and lines[i + 1].startswith("```"):
            options = []
            for word in shlex.split(m.group(1)):
                key, _, value = word.partition("=")
                options.append((key, value))
            j = i + 2
            body = []
            while j < len(lines) and not lines[j].startswith("```"):
                body.append(lines[j])
                j += 1
            blocks.append(Block(readme, i + 2, "\n".join(body) + "\n", options))
            i = j
        elif m:
            raise SystemExit("readme_runner: %s:%d: marker not followed by a ``` block" % (readme, i + 1))
        i += 1
    return blocks


def advertised(env):
    names = set()
    for cmd in (["rostopic", "list"], ["rosservice", "list"]):
        try:
            out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=10).stdout
            names.update(out.split())
        except (subprocess.TimeoutExpired, OSError):
            pass
    return names


def main():
    files = [a for a in sys.argv[1:] if not a.startswith("--")] or [os.path.join(ROOT, f) for f in DEFAULT_FILES]
    keep_going = "--keep-going" in sys.argv
    blocks = []
    for readme in files:
        found = parse(readme)
        if not found:
            print("readme_runner: no runnable block in %s" % readme)
            return 1
        blocks += found
    if "--list" in sys.argv:
        for b in blocks:
            print("%s:%d %s\n%s" % (b.path, b.line, " ".join(k + ("=" + v if v else "") for k, v in b.options), b.text))
        print("readme_runner: %d blocks in %d files (%s)" % (len(blocks), len(files), ", ".join(
            "%s: %d" % (f, sum(1 for b in blocks if b.path == f)) for f in files)))
        return 0

    build = os.environ.get("BUILD_DIR", os.path.join(ROOT, "build"))
    ros_home = os.path.join(build, "ros_home", "readme_runner")
    os.makedirs(os.path.join(ros_home, "log"), exist_ok=True)
    env = dict(os.environ)
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    env["ROS_HOME"] = ros_home
    env["ROS_LOG_DIR"] = os.path.join(ros_home, "log")
    master = "http://localhost:%d" % free_port()
    env["ROS_MASTER_URI"] = master
    work = tempfile.mkdtemp(prefix="readme_runner.", dir=build if os.path.isdir(build) else None)
    background = []
    failures = 0
    passed = False
    roscore = subprocess.Popen(["roscore", "-p", master.rsplit(":", 1)[1]], env=env, cwd=ROOT,
                               stdout=open(os.path.join(work, "roscore.log"), "w"), stderr=subprocess.STDOUT,
                               start_new_session=True)
    try:
        deadline = time.time() + 30
        while time.time() < deadline and "/rosout" not in advertised(env):
            time.sleep(0.5)
        for n, block in enumerate(blocks, 1):
            where = "%s:%d" % (os.path.relpath(block.path, ROOT), block.line)
            timeout = float(block.get("timeout", "60"))
            started = time.time()
            if block.has("setup"):
                script = block.text + "\nenv -0\n"
                done = subprocess.run(["bash", "-c", script], env=env, cwd=ROOT, capture_output=True, timeout=timeout)
                if done.returncode != 0:
                    print("FAIL %s (setup): exit %d\n%s" % (where, done.returncode, done.stderr.decode()))
                    return 1
                fresh = dict(item.split("=", 1) for item in done.stdout.decode().split("\0") if "=" in item)
                fresh["ROS_MASTER_URI"] = master  # the private master, whatever the setup says
                fresh["ROS_HOME"], fresh["ROS_LOG_DIR"] = env["ROS_HOME"], env["ROS_LOG_DIR"]
                env = fresh
                print("ok   %s setup" % where)
                continue
            if block.has("background"):
                log_path = os.path.join(work, "background_%d.log" % n)
                proc = subprocess.Popen(["bash", "-c", block.text], env=env, cwd=ROOT, stdout=open(log_path, "w"),
                                        stderr=subprocess.STDOUT, start_new_session=True)
                background.append(proc)
                name = block.get("wait")
                while name and name not in advertised(env):
                    if proc.poll() is not None or time.time() - started > timeout:
                        print("FAIL %s: background block %s (output in %s):\n%s%s" % (
                            where, "exited" if proc.poll() is not None else "never advertised " + name,
                            log_path, block.text, open(log_path).read()[-3000:]))
                        return 1
                    time.sleep(0.5)
                print("ok   %s background%s (%.1f s)" % (where, " until " + name if name else "", time.time() - started))
                continue
            try:
                done = subprocess.run(["bash", "-c", block.text], env=env, cwd=ROOT, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, timeout=timeout, start_new_session=True)
                output, code = done.stdout.decode(errors="replace"), done.returncode
            except subprocess.TimeoutExpired as e:
                output, code = (e.stdout or b"").decode(errors="replace"), None
            problems = []
            if code is None:
                problems.append("timed out after %.0f s" % timeout)
            else:
                want = block.get("exit", "0")
                if want != "any" and code != int(want):
                    problems.append("exit status %d, expected %s" % (code, want))
            for pattern in block.all("expect"):
                if not re.search(pattern, output, re.MULTILINE):
                    problems.append("output does not match /%s/" % pattern)
            if problems:
                failures += 1
                print("FAIL %s: %s\n--- block\n%s--- output (last 3000 characters)\n%s" % (
                    where, "; ".join(problems), block.text, output[-3000:]))
                if not keep_going:
                    return 1
            else:
                print("ok   %s (%.1f s)" % (where, time.time() - started))
        print("readme_runner: %d blocks in %d files, %d failed" % (len(blocks), len(files), failures))
        passed = failures == 0
        return 0 if passed else 1
    finally:
        for proc in reversed(background):
            stop(proc)
        stop(roscore)
        if passed:
            shutil.rmtree(work, ignore_errors=True)  # the logs are kept only when something failed
        else:
            print("readme_runner: logs of the background blocks and roscore in %s" % work)


if __name__ == "__main__":
    sys.exit(main())
