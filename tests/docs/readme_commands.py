#!/usr/bin/env python3
"""The README's commands, run as a user would (the doc test docs.ReadmeCommands).

First checks that every relative markdown link of the pages below names an existing file (and,
for a link into a markdown page, an existing heading); a broken link fails the test, naming the
page and the link.

Then extracts the ```sh blocks of README.md, client/README.md and every docs/*.md page (sorted),
keeps the commands that can run on this machine (the server, the `primlabel` CLI, the uploader
on files, the load generator), and runs them from a scratch directory laid out like a checkout
(build/bin, build/models, scan.pcd, scans/) against a primlabel-server on 127.0.0.1. Each must
exit 0.

Rewritten only where the machine differs from the example: `labeler:50051` and `HOST:PORT` name
the server started here, `HOST:METRICS_PORT` its /metrics, and the ports 50051 / 9464 become
free ones (ctest runs suites side by side); bare tool names get build/bin/. The load
generator's examples get two of its own flags so the whole run stays bounded (< 60 s):
--max-duration 2 per step and --max-points 5000 per cloud (a full 85k-point scan takes ~2 s to
label on two cores, and a sweep to 7 callers would queue for tens of seconds).
Commands that cannot end by themselves (--watch) or need another machine (ssh) are listed as
skipped. The commands the issue's user tried must be among those run, in any of the pages: the
server start (exactly one across them all), `info`, `label`, the load generator sweep; pages that
no longer have them fail the test.

usage: readme_commands.py SOURCE_DIR BUILD_DIR
Model repository: BUILD_DIR/models when it holds tabletop-lms400 (after `deploy/setup.sh run`),
else a small node-only model is trained for the run (~5 s) and served under both default names,
tabletop-lms400 and tabletop-kinect, with `default_model` naming tabletop-lms400, so the server
sees two models and a declared default as it does after setup.sh.
"""

import glob
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

FIXED_DOCS = ["README.md", "client/README.md"]
DOCS_GLOB = "docs/*.md"
TOOLS = ["primlabel-server", "primlabel-loadgen", "primlabel-upload", "primlabel"]
SKIP = [("--watch", "runs until a signal"), ("ssh ", "needs another machine"),
        ("--frame", "pipes to another machine")]
REQUIRED = {  # what the user tried: (description, pattern over the command)
    "server start": r"primlabel-server .*--models build/models",
    "info": r"primlabel .*\binfo tabletop-lms400\b",
    "label": r"primlabel .*\blabel scan\.pcd\b",
    "loadgen sweep": r"primlabel-loadgen .*--concurrency-range",
}
LOADGEN_CAPS = " --max-duration 2 --max-points 5000"
COMMAND_TIMEOUT_S = 45
BUDGET_S = 100        # the whole run, including training and the server start


def doc_pages(source):
    """README.md, client/README.md and every docs/*.md page, as paths relative to SOURCE."""
    pages = sorted(os.path.relpath(p, source) for p in glob.glob(os.path.join(source, DOCS_GLOB)))
    return FIXED_DOCS + pages


def without_code_blocks(text):
    """The text without its fenced code blocks (their lines are neither headings nor links)."""
    return re.sub(r"^(```|~~~).*?^\1[^\n]*$", "", text, flags=re.S | re.M)


def without_code(text):
    """The text without code blocks and inline code spans (their brackets are no links)."""
    return re.sub(r"(`+)(?:(?!\1).)+?\1", "", without_code_blocks(text))


def heading_anchors(text):
    """GitHub's anchors of a page's headings: lower case, punctuation dropped, spaces as '-'."""
    anchors, seen = set(), {}
    for title in re.findall(r"^#{1,6}[ \t]+(.+?)[ \t#]*$", without_code_blocks(text), re.M):
        title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)  # a link's text
        slug = re.sub(r"[^\w\- ]", "", title.replace("`", "").lower()).replace(" ", "-")
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        anchors.add(slug if count == 0 else f"{slug}-{count}")
    return anchors


def broken_links(source, pages):
    """(page, link, why) for every relative link of PAGES whose file or heading does not exist."""
    broken = []
    for page in pages:
        with open(os.path.join(source, page)) as f:
            text = f.read()
        for target in re.findall(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)",
                                 without_code(text)):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):  # http:, https:, mailto:
                continue
            path, _, anchor = target.partition("#")
            resolved = os.path.normpath(os.path.join(source, os.path.dirname(page), path)) \
                if path else os.path.join(source, page)
            if not os.path.exists(resolved):
                broken.append((page, target, "no such file"))
            elif anchor and resolved.endswith(".md"):
                with open(resolved) as f:
                    if anchor not in heading_anchors(f.read()):
                        broken.append((page, target, f"no heading #{anchor} in "
                                       + os.path.relpath(resolved, source)))
    return broken


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def sh_commands(text):
    """Commands of the ```sh blocks: continuation lines joined, comments dropped."""
    commands = []
    for block in re.findall(r"^```sh\n(.*?)^```", text, re.S | re.M):
        pending = ""
        for line in block.splitlines():
            if pending:
                line = pending + " " + line.strip()
                pending = ""
            if line.rstrip().endswith("\\"):
                pending = line.rstrip()[:-1].rstrip()
                continue
            line = re.sub(r"\s+#.*$", "", line).strip()
            if line and not line.startswith("#"):
                commands.append(line)
    return commands


def tool_of(command):
    first = shlex.split(command)[0]
    name = os.path.basename(first)
    return name if name in TOOLS and first in (name, "build/bin/" + name) else None


def rewrite(command, port, metrics_port):
    for old, new in [("labeler:50051", f"127.0.0.1:{port}"), ("HOST:PORT", f"127.0.0.1:{port}"),
                     ("HOST:METRICS_PORT", f"127.0.0.1:{metrics_port}"),
                     ("127.0.0.1:50051", f"127.0.0.1:{port}"),
                     ("127.0.0.1:9464", f"127.0.0.1:{metrics_port}")]:
        command = command.replace(old, new)
    if not command.startswith("build/bin/"):
        command = "build/bin/" + command
    if tool_of(command) == "primlabel-loadgen":
        command += LOADGEN_CAPS
    return command


def run(command, cwd, log):
    start = time.monotonic()
    try:
        done = subprocess.run(["bash", "-c", command], cwd=cwd, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, timeout=COMMAND_TIMEOUT_S, text=True)
        code, output = done.returncode, done.stdout
    except subprocess.TimeoutExpired as e:
        code, output = "timeout", (e.stdout or b"").decode(errors="replace")
    seconds = time.monotonic() - start
    log.write(f"$ {command}\n{output}[exit {code}, {seconds:.1f} s]\n\n")
    return code, output, seconds


def model_repository(build_dir, work, bin_dir):
    models = os.path.join(build_dir, "models")
    if os.path.isdir(os.path.join(models, "tabletop-lms400")):
        return models, "the default models in " + models
    models = os.path.join(work, "trained-models")
    trained = os.path.join(models, "tabletop-lms400", "1", "model.plm")
    os.makedirs(os.path.dirname(trained))
    subprocess.run([os.path.join(bin_dir, "primlabel-train"), "--synth-train", "1",
                    "--synth-val", "0", "--sensor", "lms400", "--kind", "node",
                    "--iterations", "30", "--name", "tabletop-lms400", "-q", "-o", trained],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)
    # The server names a model by its directory.
    os.makedirs(os.path.join(models, "tabletop-kinect", "1"))
    shutil.copy(trained, os.path.join(models, "tabletop-kinect", "1", "model.plm"))
    # A declared default (the file `deploy/setup.sh default-model` writes); older servers skip it.
    with open(os.path.join(models, "default_model"), "w") as f:
        f.write("tabletop-lms400\n")
    return models, "a small node-only model trained for this run"


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    source, build_dir = (os.path.abspath(a) for a in sys.argv[1:])
    bin_dir = os.path.join(build_dir, "bin")
    began = time.monotonic()
    docs = doc_pages(source)
    print("pages: " + ", ".join(docs))
    broken = broken_links(source, docs)
    for page, link, why in broken:
        print(f"FAIL broken link in {page}: ({link}): {why}")
    if broken:
        return 1

    commands = []
    for doc in docs:
        with open(os.path.join(source, doc)) as f:
            commands += [(doc, c) for c in sh_commands(f.read()) if tool_of(c)]

    missing = [what for what, pattern in REQUIRED.items()
               if not any(re.search(pattern, c) for _, c in commands)]
    if missing:
        print("commands not found in the pages: " + ", ".join(missing))
        return 1

    work = tempfile.mkdtemp(prefix="primlabel-readme-")
    server = None
    failures = 0
    try:
        os.makedirs(os.path.join(work, "build"))
        os.symlink(bin_dir, os.path.join(work, "build", "bin"))
        models, where = model_repository(build_dir, work, bin_dir)
        os.symlink(models, os.path.join(work, "build", "models"))
        print(f"models: {where}")
        # A held-out synthetic LMS400 scan (a test seed) as scan.pcd, and scans/ for the uploader.
        subprocess.run([os.path.join(bin_dir, "primlabel-synth"), "--scene", "table", "--sensor",
                        "lms400", "--seed", "3000", "-q", "-o", os.path.join(work, "scan.pcd")],
                       check=True, timeout=60)
        os.makedirs(os.path.join(work, "scans"))
        shutil.copy(os.path.join(work, "scan.pcd"), os.path.join(work, "scans", "scan.pcd"))

        port, metrics_port = free_port(), free_port()
        log = open(os.path.join(work, "commands.log"), "w")
        starts = [c for _, c in commands if tool_of(c) == "primlabel-server"]
        if len(starts) != 1:
            print(f"expected one server command in the pages, found {len(starts)}")
            return 1
        server_log = open(os.path.join(work, "server.log"), "w")
        server_command = rewrite(starts[0], port, metrics_port)
        print(f"start: {server_command}")
        server = subprocess.Popen(["bash", "-c", "exec " + server_command], cwd=work,
                                  stdout=server_log, stderr=subprocess.STDOUT,
                                  env=dict(os.environ, PRIMLABEL_DRAIN_SECONDS="2"))
        deadline = time.monotonic() + 30
        while "event=listening" not in open(server_log.name).read():
            if server.poll() is not None or time.monotonic() > deadline:
                print("FAIL the server did not start:\n" + open(server_log.name).read())
                return 1
            time.sleep(0.1)

        for doc, command in commands:
            if tool_of(command) == "primlabel-server":
                continue
            skip = next((why for flag, why in SKIP if flag in command), None)
            if skip:
                print(f"skip ({skip}): {doc}: {command}")
                continue
            if time.monotonic() - began > BUDGET_S:
                print(f"FAIL over the {BUDGET_S} s budget before: {command}")
                failures += 1
                break
            rewritten = rewrite(command, port, metrics_port)
            code, output, seconds = run(rewritten, work, log)
            status = "ok  " if code == 0 else "FAIL"
            print(f"{status} exit {code} in {seconds:.1f} s: {doc}: {command}")
            if code != 0:
                failures += 1
                print("     ran: " + rewritten)
                for line in output.strip().splitlines()[-5:]:
                    print("     | " + line)
        server.send_signal(signal.SIGTERM)
        try:
            code = server.wait(timeout=15)
        except subprocess.TimeoutExpired:
            code = "no exit within 15 s"
        print(f"{'ok  ' if code == 0 else 'FAIL'} the server stopped on SIGTERM: exit {code}")
        failures += code != 0
        server = None
    finally:
        if server is not None:
            server.kill()
            server.wait()
        shutil.rmtree(work, ignore_errors=True)
    print(f"{failures} failed, {time.monotonic() - began:.1f} s in all")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
