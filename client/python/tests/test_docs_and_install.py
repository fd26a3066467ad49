"""The README's Python example runs as written; `cmake --install --component python` gives a
package that works outside the build tree, with the .proto files beside it; and pip installs the
build's package offline into a venv over Debian's grpcio, numpy and protobuf."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import primlabel
from conftest import SOURCE_DIR, binary, run


def readme_example() -> str:
    text = (SOURCE_DIR / "client" / "README.md").read_text()
    section = text.split("## The Python client", 1)[1]
    match = re.search(r"```python\n(.*?)```", section, re.S)
    assert match, "client/README.md has no Python example"
    return match.group(1)


def test_readme_example_runs(server, scan, tmp_path):
    shutil.copy(scan, tmp_path / "scan.pcd")
    example = tmp_path / "example.py"
    example.write_text(readme_example())
    package_root = Path(primlabel.__file__).resolve().parents[1]
    env = dict(os.environ, PRIMLABEL_SERVER=server.address, PYTHONPATH=str(package_root))
    result = subprocess.run([sys.executable, str(example)], cwd=tmp_path, env=env, timeout=60,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("SERVING ['tiny']\n"), result.stdout
    labeled = primlabel.pcd.read(tmp_path / "scan_labeled.pcd")
    with primlabel.Client(server.address) as client:
        expected = client.label(primlabel.pcd.read(scan))
    np.testing.assert_array_equal(labeled.label, expected.labels)
    assert sorted(n for n in labeled.fields if n.startswith("prob_")) == sorted(
        primlabel.probability_field_name(c.name, c.id) for c in expected.model_classes)


def test_the_top_readme_s_python_example_runs(server, scan, tmp_path):
    text = (SOURCE_DIR / "README.md").read_text().split("### Python", 1)[1]
    example = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    assert "127.0.0.1:50051" in example
    (tmp_path / "example.py").write_text(example.replace("127.0.0.1:50051", server.address))
    shutil.copy(scan, tmp_path / "scan.pcd")
    package_root = Path(primlabel.__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(package_root))
    result = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, env=env, timeout=60,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("tiny default "), result.stdout


def test_installed_package_works_outside_the_build(server, tmp_path):
    build = os.environ.get("PRIMLABEL_BUILD_DIR")
    cmake = os.environ.get("PRIMLABEL_CMAKE", "cmake")
    if not build:
        pytest.skip("PRIMLABEL_BUILD_DIR is not set (CTest sets it)")
    prefix = tmp_path / "prefix"
    run(cmake, "--install", build, "--prefix", prefix, "--component", "python")
    packages = [p.parent.parent for p in prefix.rglob("primlabel/__init__.py")]
    assert len(packages) == 1, packages
    for stub in ("v1/labeling_pb2.py", "v1/labeling_pb2_grpc.py", "v1/model_pb2.py"):
        assert (packages[0] / "primlabel" / stub).exists(), stub
    for proto in ("labeling.proto", "model.proto"):
        assert (prefix / "share/primlabel/proto/primlabel/v1" / proto).exists(), proto
    # Only the installed copy on the path, from a directory outside the source and build trees.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(packages[0])
    code = ("import sys, primlabel; print(primlabel.__file__); "
            f"print(primlabel.Client({server.address!r}).health().name)")
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, timeout=60,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    installed, health = result.stdout.splitlines()
    assert Path(installed).resolve().is_relative_to(prefix.resolve())
    assert health == "SERVING"


def test_pip_installs_the_built_package_offline_into_a_venv(server, tmp_path):
    # The build's python/ (package, stubs and the pyproject.toml CMake writes) installs with pip
    # and nothing but Debian's packages: setuptools builds it, and the dependencies it declares
    # (grpcio, numpy, protobuf) are satisfied by python3-grpcio, -numpy and -protobuf, seen
    # through --system-site-packages. A copy, so pip's build files stay out of the build tree.
    root = Path(os.environ.get("PRIMLABEL_PYTHON_ROOT") or Path(primlabel.__file__).parents[1])
    if not (root / "pyproject.toml").exists():
        pytest.fail(f"{root} has no pyproject.toml (client/python/CMakeLists.txt writes it)")
    missing = subprocess.run(["/usr/bin/python3", "-c", "import ensurepip, setuptools, wheel"],
                             capture_output=True, text=True, timeout=60)
    if missing.returncode != 0:
        pytest.skip("needs python3-venv, python3-setuptools and python3-wheel "
                    "(deploy/setup.sh test installs them)")
    source = tmp_path / "python"
    shutil.copytree(root, source, ignore=shutil.ignore_patterns("__pycache__", "build",
                                                                "*.egg-info"))
    venv = tmp_path / "venv"
    run("/usr/bin/python3", "-m", "venv", "--system-site-packages", venv, timeout=120)
    python = venv / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH" and not k.startswith("PIP_")}
    result = subprocess.run([str(python), "-m", "pip", "install", "--no-build-isolation",
                             "--no-index", "--no-cache-dir", str(source)],
                            cwd=tmp_path, env=env, timeout=180, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    code = ("import primlabel, primlabel.v1.labeling_pb2 as pb, primlabel.v1.labeling_pb2_grpc; "
            "print(primlabel.__file__); print(primlabel.__version__); "
            "print(pb.LabelSummary.DESCRIPTOR.full_name); "
            f"print(primlabel.Client({server.address!r}).health().name)")
    result = subprocess.run([str(python), "-c", code], cwd=tmp_path, env=env, timeout=60,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    installed, version, message, health = result.stdout.splitlines()
    assert Path(installed).resolve().is_relative_to(venv.resolve())
    assert version == primlabel.__version__ and re.fullmatch(r"\d+\.\d+\.\d+", version)
    assert message == "primlabel.v1.LabelSummary" and health == "SERVING"
    # pip records the declared dependencies, and finds them all installed (Debian's).
    result = subprocess.run([str(python), "-m", "pip", "show", "primlabel"], env=env, timeout=60,
                            capture_output=True, text=True)
    requires = next(line for line in result.stdout.splitlines() if line.startswith("Requires:"))
    assert {r.strip() for r in requires.split(":", 1)[1].split(",")} == {
        "grpcio", "numpy", "protobuf"}
    result = subprocess.run([str(python), "-m", "pip", "check"], env=env, timeout=60,
                            capture_output=True, text=True)
    assert "primlabel" not in result.stdout, result.stdout
