#!/usr/bin/env python3
"""Offline checks of Penumbra's deployment files (deploy/), runnable with Debian 12 packages only.

    deploy_lint.py --binary-dir BUILD all                 every check on the repository's files
    deploy_lint.py --binary-dir BUILD docker [--dockerfile F ...]
    deploy_lint.py --binary-dir BUILD compose [--compose F]
    deploy_lint.py --binary-dir BUILD k8s [--manifest F ...]   (plain files: no kustomize)
    deploy_lint.py --binary-dir BUILD systemd [--unit F ...]

BUILD is a build folder with the farm on (server/penumbra-coordinator, worker/penumbra-worker,
client/penumbra): the files are checked against the daemons' real flags (their --help), the
binaries' shared libraries (DT_NEEDED -> Debian package) and ports.

Rules (each problem is printed as "file: RULE: message"; the exit status is 1 when any is found):
  Dockerfiles (hadolint is not in Debian 12; these are the rules of it that matter here, plus
  checks against the build):
    DF-FROM      every FROM is pinned to a tag (or digest), never `latest`; bases are debian:12.x
    DF-USER      the final stage runs as a named non-root USER
    DF-HEALTH    the final stage has a HEALTHCHECK; an HTTP check targets /healthz on the
                 --http-listen port; the tool it runs is installed
    DF-APT       apt-get install with -y and --no-install-recommends; the same RUN removes
                 /var/lib/apt/lists/*; no lone apt-get update; no -dev packages at run time
    DF-COPY      COPY sources exist in the repository; COPY --from names a stage; files copied
                 out of the build folder exist in BUILD and are built by the build stage
    DF-ADD       no ADD (COPY is explicit); no sudo
    DF-CMD       ENTRYPOINT is a copied binary, exec form; every --flag in ENTRYPOINT/CMD exists
    DF-PORT      EXPOSE lists exactly the ports the command listens on
    DF-VOLUME    the VOLUME is the coordinator's --data-dir
    DF-LIBS      every shared library the binary needs comes from a package installed in the
                 final stage (or the base image's libc6, libgcc-s1, libstdc++6)
  compose.yaml: CO-* (tags, Dockerfiles, flags, volume at --data-dir, three workers, the
    workers' coordinator address, health check)
  Kubernetes: K8S-SCHEMA every object against the API models of python3-kubernetes (Kubernetes
    1.22 OpenAPI: unknown fields, wrong types, required fields, enum values), with the fields
    added since then declared in SCHEMA_EXTENSIONS (probe `grpc`; autoscaling/v2 is the
    v2beta2 schema promoted unchanged); kustomize overlays rendered by a small built-in
    subset (resources, namespace, images, replicas, strategic-merge patches) that refuses
    what it does not implement; K8S-REF cross references (selectors, ports, Services,
    volumes, HPA target, Secrets documented in deploy/README.md, files under mounts);
    K8S-FLAG args against --help; K8S-PROBE probe ports.
  systemd: SD-VERIFY `systemd-analyze verify` (binaries pointed at BUILD); SD-FLAG ExecStart
    flags; SD-HARDEN NoNewPrivileges, ProtectSystem=strict, a non-root user, Restart, and the
    state/cache folder the command uses.
"""
import argparse
import copy
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

BINARIES = {  # installed name -> path in the build folder
    "penumbra-coordinator": "server/penumbra-coordinator",
    "penumbra-worker": "worker/penumbra-worker",
    "penumbra": "client/penumbra",
}
# Modules the binaries open at run time (not DT_NEEDED, so ldd does not show them): file name ->
# (path in the build folder, ninja target). The binaries look for them in ../lib/penumbra/.
MODULES = {"libpenumbra_oiio.so": ("lib/libpenumbra_oiio.so", "penumbra_oiio")}
MODULE_DIR = "/usr/local/lib/penumbra/"
IMAGE_BINARY = {"penumbra/coordinator": "penumbra-coordinator", "penumbra/worker": "penumbra-worker"}
BASE_IMAGE_PACKAGES = {"libc6", "libgcc-s1", "libstdc++6"}


class Report:
    def __init__(self):
        self.problems = []
        self.files = set()

    def add(self, where, rule, message):
        self.problems.append(f"{where}: {rule}: {message}")

    def print(self):
        for problem in self.problems:
            print(problem)
        print(f"deploy_lint: {len(self.files)} files checked, {len(self.problems)} problems")


class Build:
    """The built daemons: their flags (from --help) and the packages of their libraries."""

    def __init__(self, binary_dir):
        self.binary_dir = Path(binary_dir).resolve() if binary_dir else None
        self._flags = {}
        self._owners = {}

    def path(self, name):
        relative = BINARIES[name] if name in BINARIES else MODULES[name][0]
        return self.binary_dir / relative if self.binary_dir else None

    def flags(self, name):
        if name not in self._flags:
            path = self.path(name)
            if path is None or not path.exists():
                self._flags[name] = None
            else:
                run = subprocess.run([str(path), "--help"], capture_output=True, text=True,
                                     timeout=30)
                self._flags[name] = set(re.findall(r"(--[a-z][a-z0-9-]*)", run.stdout + run.stderr))
        return self._flags[name]

    def check_flags(self, report, where, rule, name, arguments):
        known = self.flags(name)
        if known is None:
            report.add(where, rule, f"cannot check flags: no built {name} in the build folder")
            return
        for argument in arguments:
            flag = argument.split("=", 1)[0]
            if flag.startswith("--") and flag not in known:
                report.add(where, rule, f"{name} has no flag {flag}")

    def owners(self, paths):
        """The Debian package owning each path that dpkg knows (one dpkg call for all of them:
        each call reads dpkg's whole database, a third of a second)."""
        unknown = sorted({p for p in paths if p not in self._owners})
        if unknown:
            found = subprocess.run(["dpkg", "-S", *unknown], capture_output=True, text=True)
            for line in found.stdout.splitlines():
                if line.startswith("diversion ") or ": " not in line:
                    continue
                package, path = line.split(": ", 1)
                # "pkg:arch" or "pkg1, pkg2" (a path shipped by several): the first package.
                self._owners[path.strip()] = package.split(",")[0].split(":")[0].strip()
            for path in unknown:
                self._owners.setdefault(path, None)
        return {p: self._owners[p] for p in paths if self._owners.get(p)}

    def needed_packages(self, name):
        """Debian packages of the binary's DT_NEEDED libraries (None when unknown)."""
        path = self.path(name)
        if path is None or not path.exists() or not shutil.which("readelf"):
            return None
        dynamic = subprocess.run(["readelf", "-d", str(path)], capture_output=True, text=True).stdout
        needed = re.findall(r"Shared library: \[([^\]]+)\]", dynamic)
        resolved = {}
        for line in subprocess.run(["ldd", str(path)], capture_output=True, text=True).stdout.splitlines():
            match = re.match(r"\s*(\S+) => (\S+)", line)
            if match:
                resolved[match.group(1)] = match.group(2)
        candidates_of = {}
        for library in needed:
            candidates = []
            if library in resolved:
                real = os.path.realpath(resolved[library])
                candidates = [real, resolved[library], real.replace("/usr/lib/", "/lib/", 1),
                              real.replace("/lib/", "/usr/lib/", 1)]
            candidates_of[library] = candidates
        owners = self.owners([c for cs in candidates_of.values() for c in cs])
        packages = {}
        for library, candidates in candidates_of.items():
            packages[library] = next((owners[c] for c in candidates if c in owners), None)
        return packages


# ---------------------------------------------------------------------------------------------
# Dockerfiles


def dockerfile_instructions(text):
    """(line number, INSTRUCTION, arguments) with continuation lines joined."""
    result, pending, start = [], "", 0
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.rstrip()
        if not pending and (not line.strip() or line.strip().startswith("#")):
            continue
        if pending and line.strip().startswith("#"):
            continue
        if not pending:
            start = number
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        pending += line
        parts = pending.strip().split(None, 1)
        result.append((start, parts[0].upper(), parts[1] if len(parts) > 1 else ""))
        pending = ""
    return result


def split_flags(arguments):
    """Leading --name=value options of an instruction, and the rest."""
    options, rest = {}, arguments.strip()
    while rest.startswith("--"):
        head, _, rest = rest.partition(" ")
        name, _, value = head[2:].partition("=")
        options[name] = value
        rest = rest.strip()
    return options, rest


def command_words(arguments):
    arguments = arguments.strip()
    if arguments.startswith("["):
        return json.loads(arguments), True
    return shlex.split(arguments), False


def listen_ports(words):
    """Ports of --listen / --http-listen host:port values in an argument list."""
    ports = {}
    for i, word in enumerate(words):
        for flag in ("--listen", "--http-listen"):
            value = None
            if word == flag and i + 1 < len(words):
                value = words[i + 1]
            elif word.startswith(flag + "="):
                value = word.split("=", 1)[1]
            if value is not None:
                match = re.search(r"(\d+)$", value)
                if match:
                    ports[flag] = int(match.group(1))
    return ports


def flag_value(words, flag):
    for i, word in enumerate(words):
        if word == flag and i + 1 < len(words):
            return words[i + 1]
        if word.startswith(flag + "="):
            return word.split("=", 1)[1]
    return None


def apt_packages(run_text):
    """Package names of the apt-get install commands in a RUN line."""
    packages = []
    for command in re.split(r"&&|;|\|\|", run_text):
        words = command.split()
        if "apt-get" in words and "install" in words:
            after = words[words.index("install") + 1:]
            packages += [w for w in after if not w.startswith("-")]
    return packages


def check_dockerfile(path, source_dir, build, report):
    report.files.add(str(path))
    where = str(path)
    instructions = dockerfile_instructions(Path(path).read_text())
    stages = []  # dicts: name, base, instructions
    for number, instruction, arguments in instructions:
        if instruction == "FROM":
            options, rest = split_flags(arguments)
            words = rest.split()
            image = words[0]
            name = words[2] if len(words) >= 3 and words[1].upper() == "AS" else None
            stage_names = {s["name"] for s in stages if s["name"]}
            if image not in stage_names:
                if "@sha256:" not in image:
                    tag = image.rsplit("/", 1)[-1].partition(":")[2]
                    if not tag:
                        report.add(f"{where}:{number}", "DF-FROM", f"{image} has no tag")
                    elif tag == "latest":
                        report.add(f"{where}:{number}", "DF-FROM", f"{image} uses latest")
                if not re.fullmatch(r"debian:12(\.\d+)?(-slim)?(@sha256:[0-9a-f]{64})?", image):
                    report.add(f"{where}:{number}", "DF-FROM",
                               f"{image} is not a pinned Debian 12 image (debian:12.N)")
            stages.append({"name": name, "base": image, "instructions": []})
        elif not stages:
            if instruction != "ARG":
                report.add(f"{where}:{number}", "DF-FROM", f"{instruction} before FROM")
        else:
            stages[-1]["instructions"].append((number, instruction, arguments))
    if not stages:
        report.add(where, "DF-FROM", "no FROM")
        return
    stage_names = {s["name"] for s in stages if s["name"]}
    build_targets = {}  # stage name -> ninja targets it builds
    for stage in stages:
        for number, instruction, arguments in stage["instructions"]:
            at = f"{where}:{number}"
            if instruction == "RUN":
                if re.search(r"\bsudo\b", arguments):
                    report.add(at, "DF-ADD", "sudo in RUN")
                installs = "apt-get install" in arguments or "setup.sh" in arguments
                updates = "apt-get update" in arguments
                if updates and "apt-get install" not in arguments:
                    report.add(at, "DF-APT", "apt-get update without an install in the same RUN")
                if "apt-get install" in arguments:
                    if not re.search(r"apt-get install[^&;]*(-y|--yes|-qq)", arguments):
                        report.add(at, "DF-APT", "apt-get install without -y")
                    if "--no-install-recommends" not in arguments:
                        report.add(at, "DF-APT", "apt-get install without --no-install-recommends")
                if (installs or updates) and "rm -rf /var/lib/apt/lists/*" not in arguments:
                    report.add(at, "DF-APT", "package install without rm -rf /var/lib/apt/lists/*")
                for match in re.finditer(r"ninja\s+-C\s+(\S+)\s+([^&;]+)", arguments):
                    build_targets.setdefault(stage["name"], set()).update(match.group(2).split())
            elif instruction == "ADD":
                report.add(at, "DF-ADD", "use COPY instead of ADD")
            elif instruction == "COPY":
                options, rest = split_flags(arguments)
                words = json.loads(rest) if rest.startswith("[") else rest.split()
                sources = words[:-1]
                if "from" in options:
                    if options["from"] not in stage_names:
                        report.add(at, "DF-COPY", f"--from={options['from']} names no stage")
                    for source in sources:
                        match = re.match(r"/src/build/(.+)$", source)
                        if match:
                            target = Path(match.group(1)).name
                            target = MODULES[target][1] if target in MODULES else target
                            if target not in build_targets.get(options["from"], set()):
                                report.add(at, "DF-COPY",
                                           f"{source}: stage {options['from']} does not build {target}")
                            if build.binary_dir and not (build.binary_dir / match.group(1)).exists():
                                report.add(at, "DF-COPY", f"{source}: no {match.group(1)} in the build")
                else:
                    for source in sources:
                        if not (Path(source_dir) / source).exists():
                            report.add(at, "DF-COPY", f"{source} does not exist in the repository")

    final = stages[-1]
    final_lines = final["instructions"]

    def last(instruction):
        found = [(n, a) for n, i, a in final_lines if i == instruction]
        return found[-1] if found else (None, None)

    number, user = last("USER")
    if user is None:
        report.add(where, "DF-USER", "the final stage has no USER (runs as root)")
    elif user.split(":")[0].strip() in ("root", "0"):
        report.add(f"{where}:{number}", "DF-USER", "the final stage runs as root")

    installed = set()
    for n, instruction, arguments in final_lines:
        if instruction == "RUN":
            for package in apt_packages(arguments):
                installed.add(package)
                if package.endswith("-dev"):
                    report.add(f"{where}:{n}", "DF-APT", f"{package}: a -dev package at run time")

    copied = {}  # destination -> source
    for n, instruction, arguments in final_lines:
        if instruction == "COPY":
            options, rest = split_flags(arguments)
            words = rest.split()
            copied[words[-1]] = words[:-1]

    number, entrypoint = last("ENTRYPOINT")
    _, cmd = last("CMD")
    words = []
    binary = None
    if entrypoint is None:
        report.add(where, "DF-CMD", "no ENTRYPOINT")
    else:
        entry_words, exec_form = command_words(entrypoint)
        if not exec_form:
            report.add(f"{where}:{number}", "DF-CMD", "ENTRYPOINT in shell form")
        if entry_words[0] not in copied:
            report.add(f"{where}:{number}", "DF-CMD", f"{entry_words[0]} is not copied into the image")
        binary = Path(entry_words[0]).name
        if binary not in BINARIES:
            report.add(f"{where}:{number}", "DF-CMD", f"{entry_words[0]} is not a Penumbra daemon")
            binary = None
        words = entry_words[1:] + (command_words(cmd)[0] if cmd else [])
        if binary:
            build.check_flags(report, where, "DF-CMD", binary, words)
    ports = listen_ports(words)
    exposed = set()
    for n, instruction, arguments in final_lines:
        if instruction == "EXPOSE":
            exposed |= {int(p.split("/")[0]) for p in arguments.split()}
    if exposed != set(ports.values()):
        report.add(where, "DF-PORT", f"EXPOSE {sorted(exposed)} but the command listens on "
                                     f"{sorted(set(ports.values()))}")
    number, health = last("HEALTHCHECK")
    if health is None or health.strip().upper() == "NONE":
        report.add(where, "DF-HEALTH", "the final stage has no HEALTHCHECK")
    else:
        for url_port, url_path in re.findall(r"https?://[^:/\s]+:(\d+)(/[^\s\"']*)?", health):
            if ports.get("--http-listen") != int(url_port):
                report.add(f"{where}:{number}", "DF-HEALTH",
                           f"checks port {url_port}, the command's --http-listen port is "
                           f"{ports.get('--http-listen')}")
            if url_path != "/healthz":
                report.add(f"{where}:{number}", "DF-HEALTH", f"checks {url_path or '/'}, not /healthz")
        if re.search(r"\bcurl\b", health) and "curl" not in installed:
            report.add(f"{where}:{number}", "DF-HEALTH", "uses curl, which the image does not install")
        if "/dev/tcp/" in health and "bash" not in health:
            report.add(f"{where}:{number}", "DF-HEALTH", "/dev/tcp needs bash")
    number, volume = last("VOLUME")
    data_dir = flag_value(words, "--data-dir")
    if data_dir is not None:
        volumes = json.loads(volume) if volume and volume.strip().startswith("[") else (volume or "").split()
        if data_dir not in volumes:
            report.add(where, "DF-VOLUME", f"--data-dir {data_dir} is not a VOLUME")
    for n, instruction, arguments in final_lines:
        if instruction == "WORKDIR" and not arguments.strip().startswith("/"):
            report.add(f"{where}:{n}", "DF-COPY", f"WORKDIR {arguments} is not absolute")
    # The modules the binaries open, where they look for them.
    if any(Path(d).name in BINARIES for d in copied):
        for module in MODULES:
            if MODULE_DIR + module not in copied:
                report.add(where, "DF-MODULE", f"the image does not copy {module} to {MODULE_DIR} "
                                               "(the binaries open it to read and write images)")
    # Shared libraries of every Penumbra binary and module copied into the image.
    for destination in copied:
        name = Path(destination).name
        if name not in BINARIES and name not in MODULES:
            continue
        packages = build.needed_packages(name)
        if packages is None:
            report.add(where, "DF-LIBS", f"cannot check the libraries of {name}: not built")
            continue
        for library, package in sorted(packages.items()):
            if library.startswith("ld-linux"):  # the dynamic loader, in libc6
                continue
            if package is None:
                report.add(where, "DF-LIBS", f"{name} needs {library}, from no known package")
            elif package.split(":")[0] not in installed | BASE_IMAGE_PACKAGES:
                report.add(where, "DF-LIBS", f"{name} needs {library} from {package}, not installed")
    return {"binary": binary, "words": words, "ports": ports}


# ---------------------------------------------------------------------------------------------
# compose


def check_compose(path, source_dir, build, report):
    report.files.add(str(path))
    where = str(path)
    document = yaml.safe_load(Path(path).read_text())
    services = document.get("services") or {}
    declared_volumes = set((document.get("volumes") or {}).keys())
    coordinators, workers = {}, {}
    for name, service in services.items():
        at = f"{where}: service {name}"
        image = service.get("image", "")
        tag = image.rsplit("/", 1)[-1].partition(":")[2]
        if not tag or tag == "latest":
            report.add(at, "CO-IMAGE", f"image {image!r} is not pinned to a version tag")
        binary = IMAGE_BINARY.get(image.partition(":")[0])
        build_spec = service.get("build")
        if build_spec:
            context = (Path(path).parent / build_spec.get("context", ".")).resolve()
            dockerfile = context / build_spec.get("dockerfile", "Dockerfile")
            if not dockerfile.exists():
                report.add(at, "CO-BUILD", f"no Dockerfile {dockerfile}")
            else:
                for _, instruction, arguments in dockerfile_instructions(dockerfile.read_text()):
                    if instruction == "ENTRYPOINT":
                        binary = Path(command_words(arguments)[0][0]).name
        if binary is None:
            report.add(at, "CO-IMAGE", "cannot tell which daemon it runs")
            continue
        command = service.get("command") or []
        if isinstance(command, str):
            command = shlex.split(command)
        build.check_flags(report, at, "CO-FLAG", binary, command)
        if binary == "penumbra-coordinator":
            coordinators[name] = (service, command)
        elif binary == "penumbra-worker":
            workers[name] = (service, command)
    if len(coordinators) != 1:
        report.add(where, "CO-SERVICES", f"{len(coordinators)} coordinator services, expected 1")
    replicas = sum(int(((s.get("deploy") or {}).get("replicas", 1))) for s, _ in workers.values())
    if replicas != 3:
        report.add(where, "CO-SERVICES", f"{replicas} workers, expected 3")
    for name, (service, command) in coordinators.items():
        at = f"{where}: service {name}"
        data_dir = flag_value(command, "--data-dir")
        mounts = {}
        for volume in service.get("volumes") or []:
            source, _, target = volume.partition(":")
            mounts[target.split(":")[0]] = source
        if data_dir not in mounts:
            report.add(at, "CO-VOLUME", f"--data-dir {data_dir} is not on a volume")
        elif not mounts[data_dir].startswith((".", "/")) and mounts[data_dir] not in declared_volumes:
            report.add(at, "CO-VOLUME", f"volume {mounts[data_dir]} is not declared")
        ports = listen_ports(command)
        published = set()
        for mapping in service.get("ports") or []:
            published.add(int(str(mapping).rsplit(":", 1)[-1].split("/")[0]))
        if not published <= set(ports.values()):
            report.add(at, "CO-PORT", f"publishes {sorted(published)}, listens on {sorted(ports.values())}")
        test = " ".join((service.get("healthcheck") or {}).get("test") or [])
        if "/healthz" not in test or f":{ports.get('--http-listen')}/" not in test:
            report.add(at, "CO-HEALTH", "no health check of /healthz on the --http-listen port")
        for worker_name, (worker, worker_command) in workers.items():
            address = flag_value(worker_command, "--coordinator") or \
                (worker.get("environment") or {}).get("PENUMBRA_COORDINATOR")
            if address != f"{name}:{ports.get('--listen')}":
                report.add(f"{where}: service {worker_name}", "CO-ADDRESS",
                           f"coordinator address {address!r}, expected {name}:{ports.get('--listen')}")


# ---------------------------------------------------------------------------------------------
# Kubernetes


# Fields newer than the python3-kubernetes models (Kubernetes 1.22): name -> type; an "X:" type
# is a structure described here (field -> (type, required)).
SCHEMA_EXTENSIONS = {
    "V1Probe": {"grpc": "X:GRPCAction"},  # Kubernetes 1.24 (beta), 1.27 (GA)
}
EXTENSION_TYPES = {
    "GRPCAction": {"port": ("int", True), "service": ("str", False)},
}
API_VERSION_MODELS = {"autoscaling/v2": "V2beta2"}  # v2 (1.23) promoted v2beta2 unchanged
CLUSTER_SCOPED = {"Namespace", "ClusterRole", "ClusterRoleBinding", "PersistentVolume",
                  "StorageClass", "CustomResourceDefinition"}


def kubernetes_models():
    import kubernetes.client
    import kubernetes.client.models as models
    configuration = kubernetes.client.Configuration()
    configuration.client_side_validation = True
    return models, configuration


def validate_value(value, type_name, path, errors, models, configuration):
    if type_name.startswith("X:"):
        structure = EXTENSION_TYPES[type_name[2:]]
        if not isinstance(value, dict):
            errors.append(f"{path}: expected an object")
            return
        for key, item in value.items():
            if key not in structure:
                errors.append(f"{path}.{key}: unknown field")
            else:
                validate_value(item, structure[key][0], f"{path}.{key}", errors, models, configuration)
        for key, (_, required) in structure.items():
            if required and key not in value:
                errors.append(f"{path}.{key}: required field missing")
        return
    if type_name.startswith("list["):
        if not isinstance(value, list):
            errors.append(f"{path}: expected a list, got {type(value).__name__}")
            return
        for i, item in enumerate(value):
            validate_value(item, type_name[5:-1], f"{path}[{i}]", errors, models, configuration)
        return
    if type_name.startswith("dict("):
        inner = type_name[5:-1].split(", ", 1)[1]
        if not isinstance(value, dict):
            errors.append(f"{path}: expected a map, got {type(value).__name__}")
            return
        for key, item in value.items():
            validate_value(item, inner, f"{path}.{key}", errors, models, configuration)
        return
    simple = {"str": str, "bool": bool, "float": (int, float), "datetime": str, "date": str}
    if type_name == "int":
        if not isinstance(value, int) or isinstance(value, bool):
            errors.append(f"{path}: expected an integer, got {value!r}")
        return
    if type_name in simple:
        if not isinstance(value, simple[type_name]) or (type_name != "bool" and isinstance(value, bool)):
            errors.append(f"{path}: expected {type_name}, got {value!r}")
        return
    if type_name == "object":  # IntOrString, Quantity, RawExtension
        return
    model = getattr(models, type_name, None)
    if model is None:
        errors.append(f"{path}: the schema has no type {type_name}")
        return
    validate_object(value, model, path, errors, models, configuration)


def validate_object(value, model, path, errors, models, configuration):
    if not isinstance(value, dict):
        errors.append(f"{path}: expected an object ({model.__name__}), got {type(value).__name__}")
        return
    json_to_attribute = {json_name: attribute for attribute, json_name in model.attribute_map.items()}
    extensions = SCHEMA_EXTENSIONS.get(model.__name__, {})
    arguments = {}
    for key, item in value.items():
        if key in extensions:
            validate_value(item, extensions[key], f"{path}.{key}", errors, models, configuration)
            continue
        if key not in json_to_attribute:
            errors.append(f"{path}.{key}: unknown field of {model.__name__[2:] if model.__name__.startswith('V1') else model.__name__}")
            continue
        attribute = json_to_attribute[key]
        validate_value(item, model.openapi_types[attribute], f"{path}.{key}", errors, models, configuration)
        arguments[attribute] = item
    # The models' constructors check required fields and enumerated values.
    try:
        model(local_vars_configuration=configuration, **arguments)
    except ValueError as error:
        errors.append(f"{path}: {error}")
    except TypeError as error:
        errors.append(f"{path}: {error}")


def validate_manifest(document, models, configuration):
    errors = []
    if not isinstance(document, dict):
        return ["the document is not an object"]
    api_version, kind = document.get("apiVersion"), document.get("kind")
    if not api_version or not kind:
        return ["apiVersion and kind are required"]
    version = api_version.split("/")[-1]
    prefix = API_VERSION_MODELS.get(api_version, version[:1].upper() + version[1:])
    model = getattr(models, prefix + kind, None)
    if model is None:
        return [f"no schema for {api_version} {kind}"]
    name = (document.get("metadata") or {}).get("name", "?")
    validate_object(document, model, f"{kind}/{name}", errors, models, configuration)
    return errors


MERGE_KEYS = {"containers": "name", "initContainers": "name", "volumes": "name", "env": "name",
              "volumeMounts": "mountPath", "volumeClaimTemplates": None}


def strategic_merge(base, patch, key=None):
    """The subset of kubectl's strategic merge patch the overlays use: maps merge, null deletes a
    key, lists of containers/volumes/env/mounts/ports merge by their key, other lists replace."""
    if isinstance(base, dict) and isinstance(patch, dict):
        if patch.get("$patch") == "replace":
            return {k: v for k, v in patch.items() if k != "$patch"}
        merged = dict(base)
        for k, v in patch.items():
            if v is None:
                merged.pop(k, None)
            elif k in merged:
                merged[k] = strategic_merge(merged[k], v, k)
            else:
                merged[k] = v
        return merged
    if isinstance(base, list) and isinstance(patch, list):
        merge_key = MERGE_KEYS.get(key)
        if key == "ports" and all(isinstance(p, dict) for p in base + patch):
            merge_key = "containerPort" if any("containerPort" in p for p in base + patch) else "port"
        if merge_key and all(isinstance(p, dict) for p in base + patch):
            merged = list(base)
            for item in patch:
                index = next((i for i, b in enumerate(merged) if b.get(merge_key) == item.get(merge_key)), None)
                if item.get("$patch") == "delete":
                    if index is not None:
                        merged.pop(index)
                elif index is None:
                    merged.append(item)
                else:
                    merged[index] = strategic_merge(merged[index], item, key)
            return merged
    return patch


def pod_specs(document):
    spec = document.get("spec") or {}
    if document.get("kind") in ("Deployment", "StatefulSet", "DaemonSet", "Job", "ReplicaSet"):
        template = spec.get("template") or {}
        return [template.get("spec") or {}]
    if document.get("kind") == "Pod":
        return [spec]
    return []


def render_kustomization(directory, report, seen=None):
    directory = Path(directory)
    seen = seen or set()
    if directory.resolve() in seen:
        raise ValueError(f"{directory}: kustomization cycle")
    seen = seen | {directory.resolve()}
    file = directory / "kustomization.yaml"
    report.files.add(str(file))
    kustomization = yaml.safe_load(file.read_text())
    supported = {"apiVersion", "kind", "resources", "namespace", "images", "replicas", "patches",
                 "patchesStrategicMerge"}
    for key in kustomization:
        if key not in supported:
            report.add(str(file), "K8S-KUSTOMIZE", f"{key}: not supported by this renderer")
    documents = []
    for resource in kustomization.get("resources") or []:
        path = directory / resource
        if path.is_dir():
            documents += render_kustomization(path, report, seen)
        elif path.exists():
            report.files.add(str(path))
            documents += [(str(path), d) for d in yaml.safe_load_all(path.read_text()) if d]
        else:
            report.add(str(file), "K8S-KUSTOMIZE", f"resource {resource} does not exist")
    patches = [{"path": p} for p in kustomization.get("patchesStrategicMerge") or []]
    patches += kustomization.get("patches") or []
    for patch in patches:
        if set(patch) - {"path", "target"}:
            report.add(str(file), "K8S-KUSTOMIZE", f"patch {patch}: only path and target are supported")
            continue
        path = directory / patch["path"]
        if not path.exists():
            report.add(str(file), "K8S-KUSTOMIZE", f"patch {patch['path']} does not exist")
            continue
        report.files.add(str(path))
        for patch_document in yaml.safe_load_all(path.read_text()):
            if not patch_document:
                continue
            target = patch.get("target") or {}
            kind = target.get("kind", patch_document.get("kind"))
            name = target.get("name", (patch_document.get("metadata") or {}).get("name"))
            matches = [i for i, (_, d) in enumerate(documents)
                       if d.get("kind") == kind and (d.get("metadata") or {}).get("name") == name]
            if not matches:
                report.add(str(path), "K8S-KUSTOMIZE", f"patch target {kind}/{name} not found")
            for i in matches:
                documents[i] = (documents[i][0], strategic_merge(documents[i][1], patch_document))
    for replica in kustomization.get("replicas") or []:
        matches = [d for _, d in documents if d.get("kind") in ("Deployment", "StatefulSet")
                   and d["metadata"].get("name") == replica["name"]]
        if not matches:
            report.add(str(file), "K8S-KUSTOMIZE", f"replicas: no workload {replica['name']}")
        for document in matches:
            document.setdefault("spec", {})["replicas"] = replica["count"]
    for image in kustomization.get("images") or []:
        for _, document in documents:
            for spec in pod_specs(document):
                for container in (spec.get("containers") or []) + (spec.get("initContainers") or []):
                    name, _, tag = container.get("image", "").partition(":")
                    if name == image["name"]:
                        name = image.get("newName", name)
                        tag = image.get("newTag", tag)
                        container["image"] = f"{name}:{tag}" if tag else name
    namespace = kustomization.get("namespace")
    if namespace:
        for _, document in documents:
            if document.get("kind") not in CLUSTER_SCOPED:
                document.setdefault("metadata", {})["namespace"] = namespace
    return [(source, copy.deepcopy(document)) for source, document in documents]


def documented_secrets(source_dir):
    readme = Path(source_dir) / "deploy" / "README.md"
    return set(re.findall(r"create secret \S+ ([a-z0-9-]+)", readme.read_text())) if readme.exists() else set()


def check_k8s_objects(documents, where, source_dir, build, report, cross_references=True):
    models, configuration = kubernetes_models()
    for source, document in documents:
        for error in validate_manifest(document, models, configuration):
            report.add(source, "K8S-SCHEMA", error)
    if not cross_references:
        return
    objects = [d for _, d in documents if isinstance(d, dict)]
    by_kind = {}
    for document in objects:
        by_kind.setdefault(document.get("kind"), {})[(document.get("metadata") or {}).get("name")] = document
    secrets = documented_secrets(source_dir) | set((by_kind.get("Secret") or {}).keys())
    pod_label_sets, container_ports = [], {}
    for document in objects:
        kind, name = document.get("kind"), (document.get("metadata") or {}).get("name")
        at = f"{where}: {kind}/{name}"
        if kind in ("Deployment", "StatefulSet"):
            spec = document.get("spec") or {}
            selector = ((spec.get("selector") or {}).get("matchLabels")) or {}
            labels = (((spec.get("template") or {}).get("metadata") or {}).get("labels")) or {}
            pod_label_sets.append(labels)
            if not selector or any(labels.get(k) != v for k, v in selector.items()):
                report.add(at, "K8S-REF", "selector does not match the pod template's labels")
            if kind == "StatefulSet":
                service = (by_kind.get("Service") or {}).get(spec.get("serviceName"))
                if service is None or (service.get("spec") or {}).get("clusterIP") != "None":
                    report.add(at, "K8S-REF", f"serviceName {spec.get('serviceName')} is not a headless Service")
            claims = {(c.get("metadata") or {}).get("name") for c in spec.get("volumeClaimTemplates") or []}
            for pod in pod_specs(document):
                if not (pod.get("securityContext") or {}).get("runAsNonRoot"):
                    report.add(at, "K8S-REF", "pods do not set runAsNonRoot")
                volumes = {v.get("name"): v for v in pod.get("volumes") or []}
                for volume in volumes.values():
                    secret = (volume.get("secret") or {}).get("secretName")
                    if secret and secret not in secrets:
                        report.add(at, "K8S-REF", f"Secret {secret} is neither in the manifests nor in "
                                                  "deploy/README.md's `kubectl create secret` steps")
                for container in pod.get("containers") or []:
                    c_at = f"{at} container {container.get('name')}"
                    image = container.get("image", "")
                    tag = image.rsplit("/", 1)[-1].partition(":")[2]
                    if not tag or tag == "latest":
                        report.add(c_at, "K8S-REF", f"image {image!r} is not pinned to a version tag")
                    binary = IMAGE_BINARY.get(image.partition(":")[0])
                    args = [str(a) for a in (container.get("command") or [])[1:] + (container.get("args") or [])]
                    if binary:
                        build.check_flags(report, c_at, "K8S-FLAG", binary, args)
                    ports = {p.get("name"): p.get("containerPort") for p in container.get("ports") or []}
                    container_ports.update({(tuple(sorted(labels.items())), k): v for k, v in ports.items()})
                    listens = listen_ports(args)
                    if set(listens.values()) != set(ports.values()):
                        report.add(c_at, "K8S-PROBE", f"container ports {sorted(ports.values())} but the "
                                                      f"command listens on {sorted(listens.values())}")
                    for probe_name in ("startupProbe", "readinessProbe", "livenessProbe"):
                        probe = container.get(probe_name)
                        if not probe:
                            continue
                        if "grpc" in probe and probe["grpc"].get("port") != listens.get("--listen"):
                            report.add(c_at, "K8S-PROBE", f"{probe_name} gRPC port {probe['grpc'].get('port')} "
                                                          f"is not the --listen port {listens.get('--listen')}")
                        if "httpGet" in probe:
                            port = probe["httpGet"].get("port")
                            port = ports.get(port, port)
                            if port != listens.get("--http-listen") or probe["httpGet"].get("path") != "/healthz":
                                report.add(c_at, "K8S-PROBE", f"{probe_name} HTTP check is not /healthz on the "
                                                              "--http-listen port")
                    mounts = [m.get("mountPath") for m in container.get("volumeMounts") or []]
                    for mount in container.get("volumeMounts") or []:
                        if mount.get("name") not in volumes and mount.get("name") not in claims:
                            report.add(c_at, "K8S-REF", f"volumeMount {mount.get('name')} names no volume")
                    for flag in ("--data-dir", "--cache-dir", "--tls-cert", "--tls-key", "--tls-ca",
                                 "--tls-client-ca", "--tokens-file", "--token-file"):
                        value = flag_value(args, flag)
                        if value and not any(value == m or value.startswith(m.rstrip("/") + "/") for m in mounts):
                            report.add(c_at, "K8S-REF", f"{flag} {value} is on no mounted volume")
                    limits = ((container.get("resources") or {}).get("limits")) or {}
                    requests = ((container.get("resources") or {}).get("requests")) or {}
                    if binary == "penumbra-worker":
                        if "cpu" not in limits or "cpu" not in requests:
                            report.add(c_at, "K8S-REF", "a worker needs CPU requests and limits")
                        threads = flag_value(args, "--threads")
                        if threads and "cpu" in limits and not str(limits["cpu"]).endswith("m") \
                                and int(threads) > float(limits["cpu"]):
                            report.add(c_at, "K8S-REF", f"--threads {threads} above the CPU limit {limits['cpu']}")
    for name, service in (by_kind.get("Service") or {}).items():
        spec = service.get("spec") or {}
        selector = spec.get("selector") or {}
        matching = [labels for labels in pod_label_sets if all(labels.get(k) == v for k, v in selector.items())]
        if not matching:
            report.add(f"{where}: Service/{name}", "K8S-REF", "selects no pod template")
        for port in spec.get("ports") or []:
            target = port.get("targetPort", port.get("port"))
            if isinstance(target, str) and not any(
                    (tuple(sorted(labels.items())), target) in container_ports for labels in matching):
                report.add(f"{where}: Service/{name}", "K8S-REF", f"targetPort {target} names no container port")
    for name, hpa in (by_kind.get("HorizontalPodAutoscaler") or {}).items():
        target = (hpa.get("spec") or {}).get("scaleTargetRef") or {}
        if target.get("name") not in (by_kind.get(target.get("kind")) or {}):
            report.add(f"{where}: HorizontalPodAutoscaler/{name}", "K8S-REF",
                       f"scaleTargetRef {target.get('kind')}/{target.get('name')} does not exist")


def check_k8s_tree(k8s_dir, source_dir, build, report):
    k8s_dir = Path(k8s_dir)
    targets = [k8s_dir / "base"] + sorted(p for p in (k8s_dir / "overlays").glob("*") if p.is_dir())
    for target in targets:
        documents = render_kustomization(target, report)
        check_k8s_objects(documents, str(target), source_dir, build, report)


# ---------------------------------------------------------------------------------------------
# systemd


def unit_settings(text):
    settings = {}
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith(("#", ";", "[")):
            continue
        key, _, value = line.partition("=")
        settings.setdefault(key.strip(), []).append(value.strip())
    return settings


def check_unit(path, build, report, verify=True):
    report.files.add(str(path))
    where = str(path)
    text = Path(path).read_text()
    settings = unit_settings(text)
    exec_start = (settings.get("ExecStart") or [""])[-1]
    words = shlex.split(exec_start)
    if not words:
        report.add(where, "SD-FLAG", "no ExecStart")
        return
    binary = Path(words[0]).name
    if binary not in BINARIES:
        report.add(where, "SD-FLAG", f"ExecStart runs {words[0]}, not a Penumbra daemon")
        return
    build.check_flags(report, where, "SD-FLAG", binary, words[1:])
    required = {"NoNewPrivileges": "yes", "ProtectSystem": "strict"}
    for key, value in required.items():
        if (settings.get(key) or [None])[-1] != value:
            report.add(where, "SD-HARDEN", f"{key}={value} missing")
    user = (settings.get("User") or [None])[-1]
    if (settings.get("DynamicUser") or ["no"])[-1] != "yes" and (user is None or user in ("root", "0")):
        report.add(where, "SD-HARDEN", "neither DynamicUser=yes nor a non-root User=")
    if not settings.get("Restart") or settings["Restart"][-1] == "no":
        report.add(where, "SD-HARDEN", "no Restart=")
    for flag, directive, root in (("--data-dir", "StateDirectory", "/var/lib/"),
                                  ("--cache-dir", "CacheDirectory", "/var/cache/")):
        value = flag_value(words, flag)
        if value is None:
            continue
        directory = (settings.get(directive) or [None])[-1]
        if directory is None or value != root + directory:
            report.add(where, "SD-HARDEN", f"{flag} {value} is not the unit's {directive} "
                                           f"({root}{directory}); ProtectSystem=strict makes it read-only")
    if verify and shutil.which("systemd-analyze") and build.binary_dir:
        with tempfile.TemporaryDirectory() as scratch:
            name = Path(path).name
            instance = name.replace("@.", "@1.") if "@." in name else name
            rewritten = text
            for installed, relative in BINARIES.items():
                rewritten = rewritten.replace(f"/usr/local/bin/{installed} ", f"{build.binary_dir / relative} ")
            (Path(scratch) / name).write_text(rewritten)
            if instance != name:
                os.symlink(Path(scratch) / name, Path(scratch) / instance)
            run = subprocess.run(["systemd-analyze", "verify", "--man=no", f"./{instance}"],
                                 cwd=scratch, capture_output=True, text=True, timeout=60)
            output = "\n".join(l for l in (run.stdout + run.stderr).splitlines() if l.strip())
            if run.returncode != 0 or output:
                report.add(where, "SD-VERIFY", output or f"systemd-analyze exited {run.returncode}")


# ---------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source-dir", default=str(Path(__file__).resolve().parent.parent))
    parser.add_argument("--binary-dir", help="a build folder with the farm on")
    parser.add_argument("what", choices=["all", "docker", "compose", "k8s", "systemd"])
    parser.add_argument("--dockerfile", action="append", default=[])
    parser.add_argument("--compose", action="append", default=[])
    parser.add_argument("--manifest", action="append", default=[])
    parser.add_argument("--unit", action="append", default=[])
    parser.add_argument("--render", help="print the rendered kustomization of this folder as YAML")
    args = parser.parse_args()
    source = Path(args.source_dir)
    build = Build(args.binary_dir)
    report = Report()
    if args.render:
        documents = render_kustomization(args.render, report)
        print(yaml.safe_dump_all([d for _, d in documents], sort_keys=False))
        return 0
    if args.what in ("all", "docker"):
        for path in args.dockerfile or sorted((source / "deploy" / "docker").glob("*.Dockerfile")):
            check_dockerfile(path, source, build, report)
    if args.what in ("all", "compose"):
        for path in args.compose or [source / "deploy" / "compose.yaml"]:
            check_compose(path, source, build, report)
    if args.what in ("all", "k8s"):
        if args.manifest:
            documents = []
            for path in args.manifest:
                report.files.add(path)
                documents += [(path, d) for d in yaml.safe_load_all(Path(path).read_text()) if d]
            check_k8s_objects(documents, "manifests", source, build, report, cross_references=False)
        else:
            check_k8s_tree(source / "deploy" / "k8s", source, build, report)
    if args.what in ("all", "systemd"):
        for path in args.unit or sorted((source / "deploy" / "systemd").glob("*.service")):
            check_unit(path, build, report)
    report.print()
    return 1 if report.problems else 0


if __name__ == "__main__":
    sys.exit(main())
