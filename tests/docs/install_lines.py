#!/usr/bin/env python3
"""Every command a page tells the reader to run is installed by that page's own apt-get line.

A page's ```sh blocks are read in order; a command word (the first word of a line, or after
`&&`, `|`, `;`) that Debian ships in a package is looked up in COMMAND_PACKAGES, and that package
must be named by an `apt-get install` line of the same page. Usage: install_lines.py SOURCE_DIR
"""
import re
import sys
from pathlib import Path

# Debian 12 (bookworm): the package that installs each command (dpkg -c of the .deb).
COMMAND_PACKAGES = {
    "roscore": "python3-roslaunch",
    "roslaunch": "python3-roslaunch",
    "rostopic": "python3-rostopic",
    "rosnode": "python3-rosnode",
    "rosparam": "python3-rosparam",
    "rosmaster": "python3-rosmaster",
    "idlc": "cyclonedds-tools",
    "ddsperf": "cyclonedds-tools",
}
PAGES = ["client/ros/README.md", "client/ros2/README.md"]


def sh_lines(text):
    lines, block = [], False
    for line in text.splitlines():
        if line.strip().startswith("```"):
            block = line.strip() == "```sh" if not block else False
            continue
        if block:
            lines.append(line)
    return lines


def main():
    root = Path(sys.argv[1])
    failures = []
    for page in PAGES:
        text = (root / page).read_text()
        lines = sh_lines(text)
        joined = re.sub(r"\\\n\s*", " ", "\n".join(lines))
        installed = set()
        for line in joined.splitlines():
            if "apt-get install" in line:
                installed.update(w for w in line.split() if re.fullmatch(r"[a-z0-9][a-z0-9.+-]+", w))
        for line in joined.splitlines():
            for part in re.split(r"&&|\||;", line.split("#")[0]):
                words = part.split()
                if not words:
                    continue
                command = words[0]
                package = COMMAND_PACKAGES.get(command)
                if package and package not in installed:
                    failures.append(f"{page}: runs `{command}` but its apt-get line lacks {package}")
    for failure in failures:
        print(failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
