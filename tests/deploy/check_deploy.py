#!/usr/bin/env python3
"""Checks the invariants of deploy/ that no Docker engine or cluster is needed for.

    check_deploy.py CHECK [ARGS...]

Exit status: 0 the check passed, 1 it found problems (one per line on stdout), 77 it could not
run here (the reason on stdout), 2 bad usage. tests/deploy/test_deploy.cpp runs every check, and
also runs them on broken copies to show that each one can fail.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

SKIP = 77
GRPC_PORT = 50051
METRICS_PORT = 9464
DEFAULT_DRAIN_SECONDS = 20


class Problems:
    def __init__(self):
        self.items = []

    def add(self, message):
        self.items.append(message)

    def check(self, condition, message):
        if not condition:
            self.add(message)

    def finish(self):
        for item in self.items:
            print(item)
        return 1 if self.items else 0


def skip(reason):
    print("skipped: " + reason)
    return SKIP


def load_yaml_documents(path):
    import yaml  # Debian: python3-yaml

    with open(path, encoding="utf-8") as stream:
        return [doc for doc in yaml.safe_load_all(stream) if doc is not None]


# ---------------------------------------------------------------------------------------------
# Dockerfile


def dockerfile_instructions(path):
    """(instruction, arguments) pairs, with continuations joined and comments dropped."""
    instructions = []
    pending = ""
    with open(path, encoding="utf-8") as stream:
        for raw in stream:
            line = raw.rstrip("\n")
            if line.lstrip().startswith("#"):
                continue
            if line.endswith("\\"):
                pending += line[:-1] + " "
                continue
            line = pending + line
            pending = ""
            if not line.strip():
                continue
            keyword, _, rest = line.strip().partition(" ")
            instructions.append((keyword.upper(), rest.strip()))
    if pending.strip():
        keyword, _, rest = pending.strip().partition(" ")
        instructions.append((keyword.upper(), rest.strip()))
    return instructions


def dockerfile_stages(path):
    """List of stages, each {"from": image, "name": alias, "instructions": [...]}."""
    stages = []
    for keyword, rest in dockerfile_instructions(path):
        if keyword == "FROM":
            words = [w for w in rest.split() if not w.startswith("--")]
            name = words[2] if len(words) >= 3 and words[1].upper() == "AS" else None
            stages.append({"from": words[0], "name": name, "instructions": []})
        elif stages:
            stages[-1]["instructions"].append((keyword, rest))
    return stages


def installed_runtime_packages(stage):
    """Package names given to apt-get install in the stage's RUN instructions."""
    packages = []
    for keyword, rest in stage["instructions"]:
        if keyword != "RUN":
            continue
        for command in re.split(r"&&|;|\|\|", rest):
            words = shlex.split(command)
            if "apt-get" not in words or "install" not in words:
                continue
            after = words[words.index("install") + 1:]
            packages += [w for w in after if not w.startswith("-")]
    return packages


def check_dockerfile(path):
    problems = Problems()
    stages = dockerfile_stages(path)
    if len(stages) < 2:
        problems.add("not a multi-stage build (%d stage)" % len(stages))
        return problems.finish()
    for stage in stages:
        problems.check(re.fullmatch(r"debian:(12|bookworm)(-slim)?(@.*)?", stage["from"]),
                       "stage FROM %s is not Debian 12" % stage["from"])
    build_stages, final = stages[:-1], stages[-1]
    build_runs = [rest for stage in build_stages for k, rest in stage["instructions"] if k == "RUN"]
    problems.check(any(re.search(r"deploy/setup\.sh\s+build\b", run) for run in build_runs),
                   "no build stage runs deploy/setup.sh build")
    problems.check(any("deploy/make-default-model.sh" in run for run in build_runs),
                   "no build stage runs deploy/make-default-model.sh")
    # The build stage compiles only what the image ships and what make-default-model.sh runs.
    build_env = " ".join(rest for stage in build_stages for k, rest in stage["instructions"]
                         if k in ("ENV", "ARG"))
    targets_match = re.search(r'\bBUILD_TARGETS="([^"]*)"', build_env)
    if not targets_match:
        problems.add("the build stage sets no BUILD_TARGETS (it would build every tool)")
    else:
        targets = set(targets_match.group(1).split())
        shipped = set(re.findall(r"/src/build/bin/([\w.-]+)",
                                 " ".join(rest for k, rest in stages[-1]["instructions"]
                                          if k == "COPY")))
        for target in sorted(shipped | {"primlabel-train"}):
            problems.check(target in targets, "BUILD_TARGETS lacks %s" % target)

    final_args = lambda key: [rest for k, rest in final["instructions"] if k == key]
    users = final_args("USER")
    if not users:
        problems.add("final stage has no USER (it would run as root)")
    else:
        user = users[-1].split(":")[0]
        problems.check(user not in ("root", "0"), "final stage runs as root (USER %s)" % users[-1])
    exposed = {port.split("/")[0] for rest in final_args("EXPOSE") for port in rest.split()}
    for port in (GRPC_PORT, METRICS_PORT):
        problems.check(str(port) in exposed, "final stage does not EXPOSE %d" % port)
    healthchecks = final_args("HEALTHCHECK")
    if not healthchecks:
        problems.add("final stage has no HEALTHCHECK")
    else:
        check = healthchecks[-1]
        problems.check(re.search(r"\bCMD\b", check) and re.search(r"\bprimlabel\b.*\bhealth\b", check),
                       "HEALTHCHECK does not run `primlabel ... health`: " + check)
    copies = " ".join(final_args("COPY"))
    for binary in ("primlabel-server", "primlabel"):
        problems.check(re.search(r"/%s(\s|$)" % re.escape(binary), copies),
                       "final stage does not copy %s" % binary)
    problems.check(re.search(r"\s/models(\s|$)", copies), "final stage does not bake /models")
    entry = " ".join(final_args("ENTRYPOINT") + final_args("CMD"))
    problems.check("primlabel-server" in entry, "ENTRYPOINT/CMD does not start primlabel-server")
    problems.check(installed_runtime_packages(final), "final stage installs no runtime packages")
    problems.check(not any(p.endswith("-dev") for p in installed_runtime_packages(final)),
                   "final stage installs -dev packages")
    return problems.finish()


def check_dockerfile_packages(path):
    """Every runtime package the final stage installs exists in the Debian archive."""
    if not shutil.which("apt-cache"):
        return skip("apt-cache not installed")
    probe = subprocess.run(["apt-cache", "show", "libc6"], capture_output=True, text=True)
    if probe.returncode != 0 or "Package:" not in probe.stdout:
        return skip("apt-cache has no package lists (run apt-get update)")
    problems = Problems()
    packages = installed_runtime_packages(dockerfile_stages(path)[-1])
    for package in packages:
        shown = subprocess.run(["apt-cache", "show", package], capture_output=True, text=True)
        problems.check(shown.returncode == 0 and "Package: " + package in shown.stdout,
                       "runtime package %s is not in the Debian archive" % package)
    return problems.finish()


def owning_package(library):
    """The Debian package that ships `library` (a path from ldd), or None."""
    real = os.path.realpath(library)
    candidates = []
    for path in (library, real):
        candidates.append(path)
        # Debian 12 is merged-/usr: ldd says /lib/..., dpkg may know /usr/lib/..., or the reverse.
        if path.startswith("/usr/"):
            candidates.append(path[len("/usr"):])
        else:
            candidates.append("/usr" + path)
    for path in candidates:
        found = subprocess.run(["dpkg", "-S", path], capture_output=True, text=True)
        if found.returncode == 0 and found.stdout:
            return found.stdout.split(":")[0].strip()
    return None


def check_dockerfile_ldd(path, binaries):
    """Every shared library of the built binaries comes from a named runtime package."""
    binaries = [b for b in binaries if os.path.isfile(b)]
    if not binaries:
        return skip("no built binary to inspect")
    if not shutil.which("ldd") or not shutil.which("dpkg"):
        return skip("ldd or dpkg not installed")
    problems = Problems()
    packages = set(installed_runtime_packages(dockerfile_stages(path)[-1]))
    for binary in binaries:
        listed = subprocess.run(["ldd", binary], capture_output=True, text=True)
        if listed.returncode != 0:
            problems.add("ldd %s failed: %s" % (binary, listed.stderr.strip()))
            continue
        for line in listed.stdout.splitlines():
            if "not found" in line:
                problems.add("%s: unresolved library: %s" % (binary, line.strip()))
                continue
            match = re.search(r"=>\s*(/\S+)", line)
            if not match:
                continue  # the vDSO and the dynamic loader itself (part of libc6)
            package = owning_package(match.group(1))
            if package is None:
                problems.add("%s: %s belongs to no Debian package" % (binary, match.group(1)))
            elif package not in packages:
                problems.add("%s: %s comes from %s, which the runtime stage does not install"
                             % (os.path.basename(binary), match.group(1), package))
    return problems.finish()


# ---------------------------------------------------------------------------------------------
# YAML, Kubernetes, Compose


def yaml_files(directory):
    for root, _, files in os.walk(directory):
        for name in sorted(files):
            if name.endswith((".yaml", ".yml")):
                yield os.path.join(root, name)


def check_yaml(directory):
    try:
        import yaml  # noqa: F401
    except ImportError:
        return skip("PyYAML not installed (Debian: python3-yaml)")
    problems = Problems()
    count = 0
    for path in yaml_files(directory):
        count += 1
        try:
            load_yaml_documents(path)
        except Exception as error:  # yaml.YAMLError, UnicodeDecodeError
            problems.add("%s does not parse: %s" % (path, str(error).replace("\n", " ")))
    problems.check(count > 0, "no YAML files under " + directory)
    return problems.finish()


def kustomize_objects(directory, problems, seen=None):
    """The objects a kustomization's resources (files and directories) define."""
    seen = seen or set()
    kustomization = os.path.join(directory, "kustomization.yaml")
    if kustomization in seen:
        return []
    seen.add(kustomization)
    if not os.path.isfile(kustomization):
        problems.add("%s has no kustomization.yaml" % directory)
        return []
    spec = load_yaml_documents(kustomization)[0]
    objects = []
    for entry in spec.get("resources", []) + spec.get("components", []):
        path = os.path.join(directory, entry)
        if os.path.isdir(path):
            objects += kustomize_objects(path, problems, seen)
        elif os.path.isfile(path):
            objects += [(path, doc) for doc in load_yaml_documents(path)]
        else:
            problems.add("%s lists %s, which does not exist" % (kustomization, entry))
    for patch in spec.get("patches", []) + spec.get("patchesStrategicMerge", []):
        path = patch.get("path") if isinstance(patch, dict) else patch
        if path and not os.path.isfile(os.path.join(directory, path)):
            problems.add("%s patches with %s, which does not exist" % (kustomization, path))
    return objects


def selector_matches(selector, labels):
    return bool(selector) and all(labels.get(k) == v for k, v in selector.items())


def env_value(container, name, config_maps):
    for env in container.get("env", []):
        if env.get("name") == name and "value" in env:
            return env["value"]
    for source in container.get("envFrom", []):
        ref = (source.get("configMapRef") or {}).get("name")
        if ref in config_maps and name in config_maps[ref]:
            return config_maps[ref][name]
    return None


def prestop_seconds(container):
    pre_stop = (container.get("lifecycle") or {}).get("preStop") or {}
    if "sleep" in pre_stop:
        return int(pre_stop["sleep"].get("seconds", 0))
    command = (pre_stop.get("exec") or {}).get("command") or []
    text = " ".join(str(c) for c in command)
    match = re.search(r"\bsleep\s+(\d+)", text)
    return int(match.group(1)) if match else 0


def check_deployment(path, deployment, config_maps, problems):
    name = deployment["metadata"]["name"]
    spec = deployment.get("spec", {})
    template = spec.get("template", {})
    pod_labels = template.get("metadata", {}).get("labels", {})
    selector = spec.get("selector", {}).get("matchLabels", {})
    problems.check(selector_matches(selector, pod_labels),
                   "Deployment %s: selector %s does not match its pod labels" % (name, selector))
    pod = template.get("spec", {})
    containers = pod.get("containers", [])
    problems.check(containers, "Deployment %s has no containers" % name)
    for container in containers:
        where = "Deployment %s container %s" % (name, container.get("name"))
        ports = {p.get("containerPort") for p in container.get("ports", [])}
        problems.check(GRPC_PORT in ports, "%s does not declare port %d" % (where, GRPC_PORT))
        problems.check(METRICS_PORT in ports, "%s does not declare port %d" % (where, METRICS_PORT))
        for probe_name in ("livenessProbe", "readinessProbe"):
            probe = container.get(probe_name)
            if not probe:
                problems.add("%s has no %s" % (where, probe_name))
                continue
            grpc = probe.get("grpc")
            if not grpc:
                problems.add("%s: %s is not a gRPC probe" % (where, probe_name))
                continue
            problems.check(grpc.get("port") == GRPC_PORT and grpc.get("port") in ports,
                           "%s: %s probes port %s, not the gRPC container port %d"
                           % (where, probe_name, grpc.get("port"), GRPC_PORT))
        for key in ("requests", "limits"):
            problems.check((container.get("resources") or {}).get(key),
                           "%s has no resource %s" % (where, key))
        drain = env_value(container, "PRIMLABEL_DRAIN_SECONDS", config_maps)
        drain = int(drain) if drain is not None else DEFAULT_DRAIN_SECONDS
        pre_stop = prestop_seconds(container)
        grace = pod.get("terminationGracePeriodSeconds", 30)
        problems.check(grace >= drain + pre_stop,
                       "%s: terminationGracePeriodSeconds %s < preStop %d + drain %d"
                       % (where, grace, pre_stop, drain))
    return pod_labels


def check_k8s(directory):
    try:
        import yaml  # noqa: F401
    except ImportError:
        return skip("PyYAML not installed (Debian: python3-yaml)")
    problems = Problems()
    objects = kustomize_objects(directory, problems)
    # Components are checked as well, whether or not the kustomization enables them.
    components = os.path.join(directory, "components")
    if os.path.isdir(components):
        for entry in sorted(os.listdir(components)):
            objects += kustomize_objects(os.path.join(components, entry), problems)
    unique = {}
    for path, doc in objects:
        for key in ("apiVersion", "kind"):
            problems.check(doc.get(key), "%s: object without %s" % (path, key))
        name = (doc.get("metadata") or {}).get("name")
        problems.check(name, "%s: %s without metadata.name" % (path, doc.get("kind")))
        unique[(doc.get("kind"), name)] = doc
    by_kind = lambda kind: [doc for (k, _), doc in unique.items() if k == kind]

    config_maps = {cm["metadata"]["name"]: cm.get("data", {}) for cm in by_kind("ConfigMap")}
    deployments = by_kind("Deployment")
    problems.check(deployments, "no Deployment")
    pod_labels = {}
    container_ports = {}
    for deployment in deployments:
        pod_labels[deployment["metadata"]["name"]] = check_deployment(
            directory, deployment, config_maps, problems)
        for container in deployment["spec"]["template"]["spec"].get("containers", []):
            for port in container.get("ports", []):
                container_ports[port.get("name")] = port.get("containerPort")

    services = by_kind("Service")
    problems.check(any(s["spec"].get("clusterIP") == "None" for s in services),
                   "no headless Service (clusterIP: None)")
    problems.check(any(s["spec"].get("clusterIP") != "None" for s in services),
                   "no ClusterIP Service")
    for service in services:
        name = service["metadata"]["name"]
        selector = service["spec"].get("selector", {})
        problems.check(any(selector_matches(selector, labels) for labels in pod_labels.values()),
                       "Service %s: selector %s matches no pod template" % (name, selector))
        for port in service["spec"].get("ports", []):
            target = port.get("targetPort", port.get("port"))
            known = target in container_ports or target in container_ports.values()
            problems.check(known, "Service %s: targetPort %s is no container port" % (name, target))

    for hpa in by_kind("HorizontalPodAutoscaler"):
        target = hpa["spec"].get("scaleTargetRef", {})
        problems.check(target.get("kind") == "Deployment" and target.get("name") in pod_labels,
                       "HPA %s scales %s, not a Deployment here" % (hpa["metadata"]["name"], target))
        resources = [m["resource"]["name"] for m in hpa["spec"].get("metrics", [])
                     if m.get("type") == "Resource"]
        problems.check("cpu" in resources, "HPA %s does not scale on CPU" % hpa["metadata"]["name"])
    problems.check(by_kind("HorizontalPodAutoscaler"), "no HorizontalPodAutoscaler")
    pdbs = by_kind("PodDisruptionBudget")
    problems.check(pdbs, "no PodDisruptionBudget")
    for pdb in pdbs:
        selector = pdb["spec"].get("selector", {}).get("matchLabels", {})
        problems.check(any(selector_matches(selector, labels) for labels in pod_labels.values()),
                       "PodDisruptionBudget %s selects no pod" % pdb["metadata"]["name"])
    return problems.finish()


# ---------------------------------------------------------------------------------------------
# .dockerignore (the build context of deploy/Dockerfile is the repository root)


def dockerignore_pattern(pattern):
    """A regular expression for one .dockerignore pattern (Go filepath.Match plus **)."""
    out, i = "", 0
    while i < len(pattern):
        if pattern.startswith("**", i):
            out += ".*"
            i += 2
            if pattern.startswith("/", i):
                out, i = out[:-2] + "(.*/)?", i + 1
        elif pattern[i] == "*":
            out, i = out + "[^/]*", i + 1
        elif pattern[i] == "?":
            out, i = out + "[^/]", i + 1
        else:
            out, i = out + re.escape(pattern[i]), i + 1
    return re.compile(out + r"\Z")


def dockerignored(rules, path):
    """Whether `path` (relative to the context) is left out: it or a parent matches, last rule wins."""
    parts = path.split("/")
    candidates = ["/".join(parts[:n]) for n in range(1, len(parts) + 1)]
    excluded = False
    for negated, regex in rules:
        if any(regex.match(candidate) for candidate in candidates):
            excluded = not negated
    return excluded


def check_dockerignore(root):
    problems = Problems()
    path = os.path.join(root, ".dockerignore")
    if not os.path.isfile(path):
        problems.add("no .dockerignore at the repository root (the build context)")
        return problems.finish()
    rules = []
    with open(path, encoding="utf-8") as stream:
        for line in stream:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            negated = line.startswith("!")
            line = os.path.normpath(line.lstrip("!").strip()).lstrip("/")
            rules.append((negated, dockerignore_pattern(line)))
    for left_out in (".git/HEAD", "build/CMakeCache.txt", "build/bin/primlabel-server",
                     "build-asan/CMakeCache.txt", "models/tabletop-lms400/1/model.plm",
                     "out/scan_labeled.pcd"):
        problems.check(dockerignored(rules, left_out), ".dockerignore keeps %s" % left_out)
    for needed in ("CMakeLists.txt", "deploy/setup.sh", "deploy/make-default-model.sh",
                   "deploy/Dockerfile", "core/CMakeLists.txt", "server/server_main.cpp",
                   "client/CMakeLists.txt", "proto/primlabel/v1/model.proto",
                   # the committed real-trained depth-camera model and its checksum
                   "deploy/models/tabletop-kinect.plm", "deploy/models/tabletop-kinect.plm.sha256"):
        problems.check(not dockerignored(rules, needed), ".dockerignore leaves out %s" % needed)
    # BuildKit prefers <Dockerfile>.dockerignore over the root file and podman ignores it: one file.
    problems.check(not os.path.exists(os.path.join(root, "deploy", "Dockerfile.dockerignore")),
                   "deploy/Dockerfile.dockerignore overrides .dockerignore under BuildKit only")
    return problems.finish()


# Compose's nginx and Prometheus: the Debian 12 packages deploy/local-proof.sh runs.
COMPOSE_DEBIAN_PACKAGES = {"nginx": "1.22", "prometheus": "2.42"}


def check_compose_versions(path):
    try:
        import yaml  # noqa: F401
    except ImportError:
        return skip("PyYAML not installed (Debian: python3-yaml)")
    problems = Problems()
    base = os.path.dirname(os.path.abspath(path))
    services = load_yaml_documents(path)[0].get("services", {})
    for package, version in COMPOSE_DEBIAN_PACKAGES.items():
        build = (services.get(package) or {}).get("build")
        if not isinstance(build, dict):
            problems.add("%s: not built from Debian's %s %s (image %s)"
                         % (package, package, version, (services.get(package) or {}).get("image")))
            continue
        dockerfile = os.path.join(base, build.get("context", "."), build.get("dockerfile", "Dockerfile"))
        if not os.path.isfile(dockerfile):
            problems.add("%s: Dockerfile %s missing" % (package, dockerfile))
            continue
        stages = dockerfile_stages(dockerfile)
        problems.check(stages and re.fullmatch(r"debian:(12|bookworm)(-slim)?", stages[-1]["from"]),
                       "%s: image is not FROM debian:12" % package)
        pins = installed_runtime_packages(stages[-1]) if stages else []
        problems.check("%s=%s.*" % (package, version) in pins,
                       "%s: Dockerfile does not install %s=%s.* (installs %s)"
                       % (package, package, version, " ".join(pins) or "nothing"))
        tag = str(services[package].get("image", ""))
        problems.check(tag.split(":")[-1].startswith(version),
                       "%s: image tag %s does not name %s" % (package, tag, version))
        # The local proof runs the host's package: it must be the pinned major.minor.
        host = subprocess.run(["dpkg-query", "-W", "-f", "${Version}", package],
                              capture_output=True, text=True) if shutil.which("dpkg-query") else None
        if host and host.returncode == 0 and host.stdout:
            problems.check(host.stdout.startswith(version + "."),
                           "%s: the local proof runs %s %s, compose pins %s"
                           % (package, package, host.stdout, version))
    return problems.finish()


def compose_replicas(compose):
    return sorted(name for name, service in compose.get("services", {}).items()
                  if str((service.get("build") or {}).get("dockerfile", "")).endswith("deploy/Dockerfile")
                  or str(service.get("image", "")).startswith("primlabel:"))


def check_compose(path):
    try:
        import yaml  # noqa: F401
    except ImportError:
        return skip("PyYAML not installed (Debian: python3-yaml)")
    problems = Problems()
    base = os.path.dirname(os.path.abspath(path))
    compose = load_yaml_documents(path)[0]
    services = compose.get("services", {})
    replicas = compose_replicas(compose)
    replica_count = sum(int((services[r].get("deploy") or {}).get("replicas", 1)) for r in replicas)
    problems.check(replica_count >= 3, "%d server replicas, want at least 3" % replica_count)
    for required in ("nginx", "prometheus"):
        problems.check(required in services, "no %s service" % required)
    named_volumes = set((compose.get("volumes") or {}).keys())
    for name, service in services.items():
        build = service.get("build")
        if build:
            context = os.path.join(base, build.get("context", ".") if isinstance(build, dict) else build)
            problems.check(os.path.isdir(context), "%s: build context %s missing" % (name, context))
            if isinstance(build, dict) and build.get("dockerfile"):
                dockerfile = os.path.join(context, build["dockerfile"])
                problems.check(os.path.isfile(dockerfile),
                               "%s: Dockerfile %s missing" % (name, dockerfile))
        for volume in service.get("volumes", []):
            source = volume.split(":")[0] if isinstance(volume, str) else volume.get("source")
            if source in named_volumes:
                continue
            problems.check(source.startswith((".", "/")),
                           "%s: volume %s is neither a file nor a declared volume" % (name, source))
            if source.startswith((".", "/")):
                problems.check(os.path.exists(os.path.join(base, source)),
                               "%s: mounts %s, which does not exist" % (name, source))
    return problems.finish()


def check_prometheus_targets(compose_path, prometheus_path, nginx_path):
    """Prometheus scrapes every replica's metrics port; nginx balances over every replica."""
    try:
        import yaml  # noqa: F401
    except ImportError:
        return skip("PyYAML not installed (Debian: python3-yaml)")
    problems = Problems()
    replicas = compose_replicas(load_yaml_documents(compose_path)[0])
    config = load_yaml_documents(prometheus_path)[0]
    targets = set()
    for job in config.get("scrape_configs", []):
        for static in job.get("static_configs", []):
            targets.update(static.get("targets", []))
    with open(nginx_path, encoding="utf-8") as stream:
        nginx = stream.read()
    upstreams = set(re.findall(r"^\s*server\s+([^\s;]+)", nginx, re.MULTILINE))
    for replica in replicas:
        problems.check("%s:%d" % (replica, METRICS_PORT) in targets,
                       "Prometheus does not scrape %s:%d" % (replica, METRICS_PORT))
        problems.check("%s:%d" % (replica, GRPC_PORT) in upstreams,
                       "nginx does not balance over %s:%d" % (replica, GRPC_PORT))
    rule_files = [os.path.join(os.path.dirname(prometheus_path), f)
                  for f in config.get("rule_files", [])]
    problems.check(rule_files, "Prometheus loads no rule files")
    for rule_file in rule_files:
        problems.check(os.path.isfile(rule_file), "rule file %s missing" % rule_file)
    return problems.finish()


def check_alert_metrics(alerts_path):
    """The alert rules cover the agreed signals, by the agreed metric names."""
    problems = Problems()
    with open(alerts_path, encoding="utf-8") as stream:
        text = stream.read()
    for needle in ('primlabel_requests_total{status!="OK"}', "primlabel_stage_seconds_bucket",
                   "primlabel_model_reload_failures_total", "primlabel_models_loaded == 0",
                   "primlabel_queue_depth"):
        problems.check(needle in text, "%s: no rule uses %s" % (alerts_path, needle))
    return problems.finish()


# ---------------------------------------------------------------------------------------------
# External validators


def check_promtool(prometheus_dir):
    if not shutil.which("promtool"):
        return skip("promtool not installed (Debian: prometheus)")
    problems = Problems()
    prometheus_dir = os.path.abspath(prometheus_dir)
    config = os.path.join(prometheus_dir, "prometheus.yml")
    commands = [["promtool", "check", "config", config]]
    for name in sorted(os.listdir(prometheus_dir)):
        path = os.path.join(prometheus_dir, name)
        if name.endswith("_test.yml"):
            commands.append(["promtool", "test", "rules", path])
        elif name != "prometheus.yml" and name.endswith((".yml", ".yaml")):
            commands.append(["promtool", "check", "rules", path])
    for command in commands:
        # promtool resolves rule_files relative to the file it checks.
        done = subprocess.run(command, capture_output=True, text=True, cwd=prometheus_dir)
        problems.check(done.returncode == 0, "%s failed:\n%s%s"
                       % (" ".join(command), done.stdout, done.stderr))
    return problems.finish()


def check_nginx(nginx_conf):
    nginx = shutil.which("nginx") or ("/usr/sbin/nginx" if os.access("/usr/sbin/nginx", os.X_OK) else None)
    if not nginx:
        return skip("nginx not installed")
    with open(nginx_conf, encoding="utf-8") as stream:
        text = stream.read()
    problems = Problems()
    for needle in ("grpc_pass", "http2", "grpc_read_timeout", "grpc_send_timeout",
                   "client_max_body_size 0"):
        problems.check(needle in text, "nginx.conf lacks %s" % needle)
    with tempfile.TemporaryDirectory(prefix="primlabel-nginx-") as prefix:
        # Compose service names do not resolve here, and the test needs no root-owned paths.
        text = re.sub(r"(^\s*server\s+)[A-Za-z0-9_.-]+(:\d+)", r"\g<1>127.0.0.1\2", text,
                      flags=re.MULTILINE)
        text = re.sub(r"^pid\s+[^;]+;", "pid %s/nginx.pid;" % prefix, text, flags=re.MULTILINE)
        temp_paths = "".join("  %s_temp_path %s/%s;\n" % (kind, prefix, kind)
                             for kind in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi"))
        text = text.replace("http {\n", "http {\n" + temp_paths, 1)
        conf = os.path.join(prefix, "nginx.conf")
        with open(conf, "w", encoding="utf-8") as stream:
            stream.write(text)
        done = subprocess.run([nginx, "-t", "-q", "-e", "stderr", "-p", prefix, "-c", conf],
                              capture_output=True, text=True, timeout=60)
        problems.check(done.returncode == 0, "nginx -t failed:\n" + done.stderr)
    return problems.finish()


CHECKS = {
    "dockerfile": check_dockerfile,
    "dockerfile-packages": check_dockerfile_packages,
    "dockerfile-ldd": lambda path, *binaries: check_dockerfile_ldd(path, binaries),
    "yaml": check_yaml,
    "k8s": check_k8s,
    "compose": check_compose,
    "compose-versions": check_compose_versions,
    "dockerignore": check_dockerignore,
    "targets": check_prometheus_targets,
    "alert-metrics": check_alert_metrics,
    "promtool": check_promtool,
    "nginx": check_nginx,
}


def main(argv):
    if len(argv) < 2 or argv[1] not in CHECKS:
        print("usage: check_deploy.py {%s} ARGS..." % "|".join(CHECKS), file=sys.stderr)
        return 2
    return CHECKS[argv[1]](*argv[2:])


if __name__ == "__main__":
    sys.exit(main(sys.argv))
