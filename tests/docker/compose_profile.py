#!/usr/bin/python3
"""Runs one profile of a compose file with podman alone (no daemon, no compose tool): the part of the Compose
Specification docker/compose.yaml uses. tests/docker/run_docker_test.sh runs the farm profile with it.

  compose_profile.py up|down COMPOSE_FILE --profile P --project NAME [--port HOST=HOST2]... -- PODMAN ARGS...

up: creates the network NAME_default (DNS: each service reachable by its name) and the named volumes NAME_VOL, then
starts the profile's services in depends_on order as containers NAME-SERVICE: image, entrypoint, command, env_file,
ports (host port HOST republished on HOST2 where --port says so), volumes; service_healthy waits for the service's
healthcheck (its CMD-SHELL run with podman exec), service_completed_successfully for the container to exit 0.
`build` is not run (the image is built beforehand) and `restart` is left to the caller. down: stops the containers
(stop_signal, stop_grace_period) in reverse order and removes them, the network and the volumes. PODMAN ARGS is the
podman command line (global options) followed, after a second `--`, by options for every `podman run`.
"""
import argparse
import os
import re
import subprocess
import sys
import time

import yaml


def parse_duration(text, default):
    """Compose durations as used here: 5s, 30s, 1m30s."""
    if text is None:
        return default
    total = 0.0
    for value, unit in re.findall(r"(\d+(?:\.\d+)?)(ms|s|m|h)", str(text)):
        total += float(value) * {"ms": 0.001, "s": 1, "m": 60, "h": 3600}[unit]
    return total


def profile_services(compose, profile):
    return {name: svc for name, svc in compose["services"].items() if profile in svc.get("profiles", [])}


def start_order(services):
    order, seen = [], set()

    def visit(name):
        if name in seen:
            return
        seen.add(name)
        for dep in dependencies(services[name]):
            if dep in services:
                visit(dep)
        order.append(name)

    for name in services:
        visit(name)
    return order


def dependencies(svc):
    deps = svc.get("depends_on", {})
    if isinstance(deps, list):
        return {d: {"condition": "service_started"} for d in deps}
    return deps


def as_list(value):
    if value is None:
        return None
    return value if isinstance(value, list) else ["sh", "-c", value]


def run(cmd, **kw):
    print("+ " + " ".join(cmd), flush=True)
    return subprocess.run(cmd, check=True, **kw)


def wait_healthy(podman, container, svc):
    check = svc.get("healthcheck")
    if not check:
        raise SystemExit(f"{container}: service_healthy without a healthcheck")
    test = check["test"]
    if test[0] == "CMD-SHELL":
        cmd = ["sh", "-c", test[1]]
    elif test[0] == "CMD":
        cmd = test[1:]
    else:
        raise SystemExit(f"{container}: healthcheck test {test[0]} not supported")
    interval = parse_duration(check.get("interval"), 30)
    retries = int(check.get("retries", 3))
    for attempt in range(retries):
        if subprocess.run(podman + ["exec", container] + cmd, stdout=subprocess.DEVNULL,
                          stderr=subprocess.DEVNULL).returncode == 0:
            print(f"{container}: healthy after {attempt + 1} checks", flush=True)
            return
        time.sleep(interval)
    raise SystemExit(f"{container}: not healthy after {retries} checks")


def up(args, compose, services, podman, run_opts):
    base = os.path.dirname(os.path.abspath(args.compose_file))
    network = f"{args.project}_default"
    run(podman + ["network", "create", network], stdout=subprocess.DEVNULL)
    port_map = dict(p.split("=") for p in args.port)
    for name in start_order(services):
        svc = services[name]
        container = f"{args.project}-{name}"
        for dep, spec in dependencies(svc).items():
            condition = spec.get("condition", "service_started")
            dep_container = f"{args.project}-{dep}"
            if condition == "service_healthy":
                wait_healthy(podman, dep_container, services[dep])
            elif condition == "service_completed_successfully":
                code = subprocess.run(podman + ["wait", dep_container], check=True, capture_output=True,
                                      text=True).stdout.strip()
                if code != "0":
                    subprocess.run(podman + ["logs", dep_container])
                    raise SystemExit(f"{dep_container} exited {code}")
                print(f"{dep_container}: completed successfully", flush=True)
        cmd = podman + ["run", "-d", "--name", container, "--network", network, "--network-alias", name] + run_opts
        for env_file in as_list_plain(svc.get("env_file")):
            cmd += ["--env-file", os.path.join(base, env_file)]
        for port in svc.get("ports", []):
            parts = str(port).split(":")
            if len(parts) == 3 and parts[1] in port_map:
                parts[1] = port_map[parts[1]]
            cmd += ["-p", ":".join(parts)]
        for volume in svc.get("volumes", []):
            source, target = volume.split(":")[:2]
            if not source.startswith(("/", ".")):
                source = f"{args.project}_{source}"
            cmd += ["-v", f"{source}:{target}"]
        if svc.get("stop_signal"):
            cmd += ["--stop-signal", svc["stop_signal"]]
        if svc.get("stop_grace_period"):
            cmd += ["--stop-timeout", str(int(parse_duration(svc["stop_grace_period"], 10)))]
        entrypoint = svc.get("entrypoint")
        if entrypoint is not None:
            entrypoint = as_list(entrypoint)
            cmd += ["--entrypoint", entrypoint[0]]
        cmd.append(svc["image"])
        if entrypoint is not None:
            cmd += entrypoint[1:]
        command = as_list(svc.get("command"))
        if command:
            cmd += command
        # Without systemd, podman logs that it cannot add a timer for an image's HEALTHCHECK: not an error here.
        print("+ " + " ".join(cmd), flush=True)
        result = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        sys.stderr.write("".join(line for line in result.stderr.splitlines(keepends=True)
                                 if "unable to get systemd connection" not in line))
        if result.returncode != 0:
            raise SystemExit(f"{container}: podman run exited {result.returncode}")


def as_list_plain(value):
    if value is None:
        return []
    return value if isinstance(value, list) else [value]


def down(args, compose, services, podman):
    for name in reversed(start_order(services)):
        container = f"{args.project}-{name}"
        grace = int(parse_duration(services[name].get("stop_grace_period"), 10))
        subprocess.run(podman + ["stop", "-t", str(grace), container], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        subprocess.run(podman + ["rm", "-f", "-v", container], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    subprocess.run(podman + ["network", "rm", "-f", f"{args.project}_default"], stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    for volume in compose.get("volumes", {}) or {}:
        subprocess.run(podman + ["volume", "rm", "-f", f"{args.project}_{volume}"], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)


def main():
    argv = sys.argv[1:]
    if "--" not in argv:
        raise SystemExit(__doc__)
    split = argv.index("--")
    rest = argv[split + 1:]
    podman, run_opts = (rest[:rest.index("--")], rest[rest.index("--") + 1:]) if "--" in rest else (rest, [])
    parser = argparse.ArgumentParser()
    parser.add_argument("action", choices=["up", "down"])
    parser.add_argument("compose_file")
    parser.add_argument("--profile", required=True)
    parser.add_argument("--project", required=True)
    parser.add_argument("--port", action="append", default=[])
    args = parser.parse_args(argv[:split])
    with open(args.compose_file, encoding="utf-8") as f:
        compose = yaml.safe_load(f)
    services = profile_services(compose, args.profile)
    if not services:
        raise SystemExit(f"no service in profile {args.profile}")
    if args.action == "up":
        up(args, compose, services, podman, run_opts)
    else:
        down(args, compose, services, podman)


if __name__ == "__main__":
    main()
