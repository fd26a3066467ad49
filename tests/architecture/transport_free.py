#!/usr/bin/env python3
"""architecture.ServiceWithoutGrpc: the transport-free layers stay free of gRPC. Usage:
transport_free.py LINKS TARGET [SOURCE_DIR ...]. Fails when TARGET reaches a gRPC library through
its links (links.txt, followed through every project library it links), or when a file under a
SOURCE_DIR includes a gRPC header (<grpc...>, <grpcpp/...> or a generated *.grpc.pb.h)."""
import os
import re
import sys

from check_links import project_library, read, report

GRPC_LIBRARY = re.compile(r"grpc", re.IGNORECASE)
GRPC_INCLUDE = re.compile(r'^\s*#\s*include\s*[<"](grpc[^>"]*|[^>"]*\.grpc\.pb\.h)[>"]', re.M)


def reached(links, target):
    seen, stack, chains = set(), [target], {target: [target]}
    while stack:
        current = stack.pop()
        for entry in links.get(current, []):
            name = project_library(entry) or entry
            if name in seen:
                continue
            seen.add(name)
            chains[name] = chains[current] + [name]
            stack.append(name)
    return seen, chains


def main():
    links = read(sys.argv[1])
    target, source_dirs = sys.argv[2], sys.argv[3:]
    errors = []
    if target not in links:
        errors.append(f"{target} is not a project library")
    libraries, chains = reached(links, target)
    for library in sorted(libraries):
        if GRPC_LIBRARY.search(library):
            errors.append(f"{target} reaches {library}: " + " -> ".join(chains[library]))
    files = 0
    for source_dir in source_dirs:
        for root, _, names in os.walk(source_dir):
            for name in names:
                if not name.endswith((".hpp", ".cpp", ".h")):
                    continue
                path = os.path.join(root, name)
                files += 1
                for match in GRPC_INCLUDE.finditer(open(path, encoding="utf-8").read()):
                    errors.append(f"{path} includes {match.group(1)}")
    return report(errors, f"{target}: {len(libraries)} libraries reached and {files} files, none of gRPC")


if __name__ == "__main__":
    sys.exit(main())
