#!/usr/bin/env python3
"""architecture.ForbiddenIncludeFails: proves the header check can fail. Takes the command that
compiles HEADER's stand-alone unit (compile_commands.json, target primlabel_*_headers), checks that
it compiles the unit, then compiles a copy that also includes FORBIDDEN (a header of a library the
target does not link) with the same command and expects the compiler to refuse it."""
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile


def main():
    commands_path, header, forbidden = sys.argv[1:4]
    unit_name = re.sub(r"[^A-Za-z0-9_]", "_", header) + ".cpp"
    entries = [e for e in json.load(open(commands_path, encoding="utf-8"))
               if e["file"].endswith("/header_check/" + unit_name)]
    if not entries:
        print(f"FAIL: no header-check unit for {header} in {commands_path}")
        return 1
    entry = entries[0]
    args = entry.get("arguments") or shlex.split(entry["command"])
    # Same compiler and flags, syntax only, no object written; the unit's path is swapped below.
    base = []
    skip = False
    for arg in args:
        if skip:
            skip = False
            continue
        if arg in ("-o", "-c"):
            skip = arg == "-o"
            continue
        if arg == entry["file"] or arg.endswith("/" + unit_name):
            continue
        base.append(arg)
    base.append("-fsyntax-only")

    def compile_unit(text):
        with tempfile.NamedTemporaryFile("w", suffix=".cpp", delete=False) as unit:
            unit.write(text)
        try:
            run = subprocess.run(base + [unit.name], cwd=entry["directory"],
                                 capture_output=True, text=True)
            return run.returncode, run.stderr
        finally:
            os.unlink(unit.name)

    code, err = compile_unit(f'#include "{header}"\n')
    if code != 0:
        print(f"FAIL: {header} alone does not compile with its own flags:\n{err}")
        return 1
    code, err = compile_unit(f'#include "{header}"\n#include "{forbidden}"\n')
    if code == 0:
        print(f"FAIL: {forbidden} compiled beside {header}: the boundary is not enforced")
        return 1
    first = next((line for line in err.splitlines() if "error" in line), err.strip())
    print(f"{header} compiles alone; adding {forbidden} is refused as it should be:\n  {first}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
