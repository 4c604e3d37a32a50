#!/usr/bin/env python3
"""Checks the deployment files against what the binaries really use.

    deploy_test.py SOURCE_DIR BUILD_DIR [unittest options]

Installs the build (`cmake --install BUILD --prefix TMP/usr/local`, the
image's layout) and reads the binaries' flags and defaults from their
`--helpfull`, the shipped configurations, docker/Dockerfile,
deploy/compose*.yaml, deploy/k8s/*.yaml and the systemd unit, and checks
that they agree: every command names an installed binary and only flags it
has, every configuration path exists in the installed tree, every port is
the one the binaries and configurations use. Validates the compose files
with docker-compose (the Compose specification's JSON schema) and the
Kubernetes manifests with tests/deploy/validate_k8s.mjs (the Kubernetes
OpenAPI schemas) where those tools are present; those two tests are skipped
otherwise. A binary whose target is not built yet (the daemon, the
emulator) has its checks skipped, and says so.
"""

import configparser
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import unittest

import yaml

SOURCE_DIR = ""
BUILD_DIR = ""
TMP = None  # tempfile.TemporaryDirectory
PREFIX = "/usr/local"  # the image's install prefix (docker/Dockerfile)
SHARE = PREFIX + "/share/cornerpose"
BINARIES = ("cornerpose_server", "cornerpose", "cornerpose_robot_client", "ur_emulator")


def src(*parts):
    return os.path.join(SOURCE_DIR, *parts)


def installed(path):
    """Where an absolute image path (/usr/local/...) is in the test install."""
    assert path.startswith(PREFIX + "/"), path
    return os.path.join(TMP.name, path.lstrip("/"))


def load_yaml(*parts):
    with open(src(*parts)) as f:
        return yaml.safe_load(f)


def load_yaml_all(*parts):
    with open(src(*parts)) as f:
        return [d for d in yaml.safe_load_all(f) if d is not None]


def port_of(address):
    """The port of host:port (or dns:///host:port)."""
    m = re.search(r":(\d+)$", address)
    if not m:
        raise ValueError(f"no port in {address!r}")
    return int(m.group(1))


_flags_cache = {}


def flags_of(binary, subcommand=()):
    """{flag name: default text} from BINARY --helpfull (absl flags), or the
    flag names in `cornerpose SUBCOMMAND... --help`; None when not installed."""
    key = (binary, *subcommand)
    if key in _flags_cache:
        return _flags_cache[key]
    path = installed(f"{PREFIX}/bin/{binary}")
    result = None
    if os.access(path, os.X_OK) and binary == "cornerpose":
        out = subprocess.run([path, *subcommand, "--help"], capture_output=True, text=True,
                             timeout=60)
        if out.returncode != 0:
            raise AssertionError(f"cornerpose {' '.join(subcommand)} --help failed:\n"
                                 f"{out.stdout}{out.stderr}")
        result = {m: "" for m in re.findall(r"^\s+--(\w+)", out.stdout, re.M)}
    elif os.access(path, os.X_OK):
        # absl prints --helpfull and exits 1.
        out = subprocess.run([path, "--helpfull"], capture_output=True, text=True, timeout=60)
        text = out.stdout + out.stderr
        result = {}
        for m in re.finditer(r"^\s+--(\w+) \((.*?)\);\s+default: (.*?);$", text, re.M | re.S):
            result[m.group(1)] = m.group(3).strip().strip('"')
        if not result:
            raise AssertionError(f"{binary} --helpfull listed no flags:\n{text[:2000]}")
    _flags_cache[key] = result
    return result


def strip_comments(text):
    """A text-format file without comments and blank lines, lines stripped."""
    lines = (re.sub(r"#.*", "", l).strip() for l in text.splitlines())
    return "\n".join(l for l in lines if l)


def textproto_field(text, name):
    """The first `name: value` in a text-format file (comments stripped)."""
    text = re.sub(r"#.*", "", text)
    m = re.search(rf"\b{name}\s*:\s*(\"[^\"]*\"|[^\s}}]+)", text)
    return m.group(1).strip('"') if m else None


def textproto_block(text, name):
    text = re.sub(r"#.*", "", text)
    m = re.search(rf"\b{name}\s*\{{([^{{}}]*)\}}", text)
    return m.group(1) if m else ""


def read(*parts):
    with open(src(*parts)) as f:
        return f.read()


def split_flags(argv):
    """[(name, value or None)] of the --flags in argv[1:]."""
    out = []
    for arg in argv[1:]:
        m = re.match(r"^--?(\w+)(?:=(.*))?$", arg, re.S)
        if m:
            out.append((m.group(1), m.group(2)))
    return out


def flag_value(argv, name):
    for n, v in split_flags(argv):
        if n == name:
            return v
    return None


class Ports:
    """The ports the binaries and shipped configurations use."""

    def __init__(self):
        server_cfg = read("deploy", "config", "server.textproto")
        self.server = port_of(textproto_field(server_cfg, "listen_address"))
        robot_cfg = read("deploy", "config", "robot_client.textproto")
        self.status = port_of(textproto_field(robot_cfg, "status_listen_address") or ":50061")
        robot = textproto_block(robot_cfg, "robot")
        self.ur = {
            "dashboard_port": int(textproto_field(robot, "dashboard_port") or 29999),
            "primary_port": int(textproto_field(robot, "primary_port") or 30001),
            "rtde_port": int(textproto_field(robot, "rtde_port") or 30004),
        }
        self.robot_server_address = textproto_field(
            textproto_block(robot_cfg, "perception"), "server_address")
        self.robot_source = textproto_field(textproto_block(robot_cfg, "perception"), "source")
        self.server_sources = re.findall(r"\bname\s*:\s*\"([^\"]+)\"",
                                         "".join(re.findall(r"sources\s*\{[^}]*\}",
                                                            strip_comments(server_cfg))))


class DeployTestCase(unittest.TestCase):

    def check_command(self, argv, where):
        """argv[0] is a shipped binary, every flag exists, --config files are installed."""
        binary = os.path.basename(argv[0])
        self.assertIn(binary, BINARIES, f"{where}: {argv[0]} is not a cornerpose binary")
        if argv[0].startswith("/"):
            self.assertEqual(argv[0], f"{PREFIX}/bin/{binary}", f"{where}: binary path")
        config = flag_value(argv, "config")
        if config is not None and config.startswith(SHARE):
            self.assertTrue(os.path.isfile(installed(config)),
                            f"{where}: {config} is not in the installed tree")
        # The command-line tool's subcommands: the words before the first flag.
        subcommand = ()
        if binary == "cornerpose":
            words = [a for a in argv[1:]]
            first_flag = next((i for i, a in enumerate(words) if a.startswith("-")), len(words))
            subcommand = tuple(words[:first_flag])
        flags = flags_of(binary, subcommand)
        if flags is None:
            print(f"note: {binary} is not built; its flags in {where} are not checked",
                  file=sys.stderr)
            return
        for name, _ in split_flags(argv):
            self.assertIn(name, flags, f"{where}: {binary} has no flag --{name}")


class InstallTest(DeployTestCase):

    def test_binaries_and_configs_installed(self):
        for b in ("cornerpose_server", "cornerpose"):
            self.assertTrue(os.access(installed(f"{PREFIX}/bin/{b}"), os.X_OK), b)
        for name in os.listdir(src("deploy", "config")):
            if name.endswith(".textproto"):
                self.assertTrue(os.path.isfile(installed(f"{SHARE}/deploy/config/{name}")), name)

    def test_config_sources_resolve_in_installed_tree(self):
        config_dir = installed(f"{SHARE}/deploy/config")
        text = re.sub(r"#.*", "", read("deploy", "config", "server.textproto"))
        directories = re.findall(r"directory\s*:\s*\"([^\"]+)\"", text)
        self.assertTrue(directories, "server.textproto names no source directory")
        for d in directories:
            full = os.path.normpath(os.path.join(config_dir, d))
            self.assertTrue(os.path.isdir(full), f"source directory {d} -> {full}")
            frames = [f for f in os.listdir(full) if f.endswith((".png", ".pcd"))]
            self.assertTrue(frames, f"no frames in {full}")

    def test_flag_defaults_match_configs(self):
        ports = Ports()
        server = flags_of("cornerpose_server")
        self.assertEqual(port_of(server["listen"]), ports.server)
        emulator = flags_of("ur_emulator")
        if emulator is not None:
            for name, port in ports.ur.items():
                self.assertEqual(int(emulator[name]), port, f"ur_emulator --{name}")


class DockerfileTest(DeployTestCase):

    def setUp(self):
        text = read("docker", "Dockerfile")
        self.lines = re.sub(r"\\\n", " ", text).splitlines()
        self.runtime = []
        stage = None
        for line in self.lines:
            if re.match(r"^FROM\s", line):
                stage = line.split()[-1]
            if stage == "runtime":
                self.runtime.append(line)

    def instruction(self, name):
        return [l.split(None, 1)[1].strip() for l in self.runtime
                if l.startswith(name + " ") or l.startswith(name + "\t")]

    def test_runtime_user_non_root_numeric(self):
        users = self.instruction("USER")
        self.assertTrue(users, "no USER in the runtime stage")
        uid = users[-1].split(":")[0]
        self.assertTrue(uid.isdigit() and int(uid) != 0, users[-1])

    def test_exposed_ports(self):
        ports = Ports()
        exposed = {int(p.split("/")[0]) for e in self.instruction("EXPOSE") for p in e.split()}
        wanted = {ports.server, ports.status, *ports.ur.values()}
        self.assertTrue(wanted <= exposed, f"EXPOSE {sorted(exposed)} lacks {wanted - exposed}")

    def test_healthcheck_and_cmd(self):
        ports = Ports()
        health = self.instruction("HEALTHCHECK")
        self.assertEqual(len(health), 1)
        argv = yaml.safe_load(health[0].split("CMD", 1)[1])
        self.assertEqual(argv[:3], ["cornerpose", "client", "health"])
        self.assertEqual(port_of(flag_value(argv, "server") or argv[argv.index("--server") + 1]),
                         ports.server)
        cmd = yaml.safe_load(self.instruction("CMD")[-1])
        self.check_command(cmd, "Dockerfile CMD")


class ComposeTest(DeployTestCase):

    def setUp(self):
        self.compose = load_yaml("deploy", "compose.yaml")
        self.camera = load_yaml("deploy", "compose.camera.yaml")
        self.services = self.compose["services"]
        self.ports = Ports()

    def test_schema(self):
        tool = shutil.which("docker-compose")
        if tool is None:
            self.skipTest("docker-compose (Debian package) not installed")
        for files in (["compose.yaml"], ["compose.yaml", "compose.camera.yaml"]):
            args = [tool]
            for f in files:
                args += ["-f", src("deploy", f)]
            out = subprocess.run(args + ["config", "-q"], capture_output=True, text=True,
                                 timeout=120)
            self.assertEqual(out.returncode, 0, f"docker-compose config {files}:\n{out.stderr}")

    def test_commands(self):
        for doc, name in ((self.compose, "compose.yaml"), (self.camera, "compose.camera.yaml")):
            for service, spec in doc["services"].items():
                if "command" in spec:
                    self.check_command(spec["command"], f"{name} {service}")
                health = spec.get("healthcheck", {}).get("test")
                if health and health[1] == "cornerpose":
                    self.check_command(health[1:], f"{name} {service} healthcheck")

    def test_one_image(self):
        images = {s.get("image") for s in self.services.values()}
        self.assertEqual(len(images), 1, images)
        for s in self.services.values():
            self.assertEqual(s["build"]["dockerfile"], "docker/Dockerfile")

    def test_perception_wiring(self):
        p = self.services["perception"]
        listen = flag_value(p["command"], "listen")
        port = port_of(listen) if listen else self.ports.server
        self.assertEqual(port, self.ports.server)
        self.assertIn(f"{port}:{port}", p["ports"])
        self.assertEqual(port_of(p["healthcheck"]["test"][-1]), port)

    def test_emulator_wiring(self):
        e = self.services["ur-emulator"]
        self.assertEqual(flag_value(e["command"], "host"), "0.0.0.0")
        for name, port in self.ports.ur.items():
            self.assertEqual(int(flag_value(e["command"], name)), port, name)
            self.assertIn(f"{port}:{port}", e["ports"])
        self.assertIn(str(self.ports.ur["dashboard_port"]), " ".join(e["healthcheck"]["test"]))

    def test_robot_client_wiring(self):
        r = self.services["robot-client"]
        cmd = r["command"]
        self.assertEqual(flag_value(cmd, "server"), f"perception:{self.ports.server}")
        self.assertEqual(flag_value(cmd, "robot_host"), "ur-emulator")
        self.assertEqual(port_of(flag_value(cmd, "status_listen")), self.ports.status)
        self.assertIn(f"{self.ports.status}:{self.ports.status}", r["ports"])
        self.assertEqual(port_of(r["healthcheck"]["test"][-1]), self.ports.status)
        self.assertEqual(os.path.basename(flag_value(cmd, "config")), "robot_client.textproto")
        # The daemon subscribes to a source the service serves.
        source = flag_value(cmd, "source") or self.ports.robot_source
        self.assertIsNone(flag_value(self.services["perception"]["command"], "source"))
        self.assertIn(source, self.ports.server_sources,
                      "the daemon's source is not one server.textproto serves")
        for dep in ("perception", "ur-emulator"):
            self.assertEqual(r["depends_on"][dep]["condition"], "service_healthy")
            self.assertIn("healthcheck", self.services[dep])

    def test_camera_override(self):
        p = self.camera["services"]["perception"]
        self.assertIn("/dev/bus/usb:/dev/bus/usb", p["devices"])
        sources = [v for n, v in split_flags(p["command"]) if n == "source"]
        self.assertEqual(len(sources), 1)
        name, _, spec = sources[0].partition("=")
        self.assertEqual(spec, "openni2:")
        r = self.camera["services"]["robot-client"]
        self.assertEqual(flag_value(r["command"], "source"), name,
                         "the daemon must subscribe to the camera's source")


class KubernetesTest(DeployTestCase):

    def setUp(self):
        self.docs = {}
        for name in sorted(os.listdir(src("deploy", "k8s"))):
            if name.endswith(".yaml") and name != "kustomization.yaml":
                for d in load_yaml_all("deploy", "k8s", name):
                    self.docs[(d["kind"], d["metadata"]["name"])] = d
        self.deployment = self.docs[("Deployment", "cornerpose-perception")]
        self.pod = self.deployment["spec"]["template"]["spec"]
        self.container = self.pod["containers"][0]
        self.ports = Ports()

    def configmap_config(self):
        cm_name = next(v["configMap"]["name"] for v in self.pod["volumes"] if "configMap" in v)
        return self.docs[("ConfigMap", cm_name)]["data"]

    def test_kustomization_lists_every_manifest(self):
        k = load_yaml("deploy", "k8s", "kustomization.yaml")
        files = {n for n in os.listdir(src("deploy", "k8s"))
                 if n.endswith(".yaml") and n != "kustomization.yaml"}
        self.assertEqual(set(k["resources"]), files)

    def test_schema(self):
        node, npm = shutil.which("node"), shutil.which("npm")
        if node is None or npm is None:
            self.skipTest("node/npm not installed")
        modules = os.path.join(BUILD_DIR, "tests", "deploy", "npm")
        if not os.path.isdir(os.path.join(modules, "node_modules", "kubernetes-models")):
            os.makedirs(modules, exist_ok=True)
            for f in ("package.json", "package-lock.json"):
                shutil.copy(src("tests", "deploy", f), modules)
            out = subprocess.run([npm, "ci", "--no-audit", "--no-fund", "--prefix", modules],
                                 capture_output=True, text=True, timeout=300)
            if out.returncode != 0:
                self.skipTest(f"npm ci failed (no registry?): {out.stderr[-500:]}")
        script = os.path.join(modules, "validate_k8s.mjs")
        shutil.copy(src("tests", "deploy", "validate_k8s.mjs"), script)
        manifests = [src("deploy", "k8s", n) for n in sorted(os.listdir(src("deploy", "k8s")))
                     if n.endswith(".yaml")]
        out = subprocess.run([node, script, *manifests], capture_output=True, text=True,
                             timeout=120)
        self.assertEqual(out.returncode, 0, out.stdout + out.stderr)

    def test_command_and_config(self):
        cmd = self.container["command"] + self.container.get("args", [])
        self.check_command(cmd, "deployment.yaml")
        config = flag_value(cmd, "config")
        mount = next(m for m in self.container["volumeMounts"] if m["name"] == "config")
        self.assertEqual(os.path.dirname(config), mount["mountPath"])
        data = self.configmap_config()
        self.assertIn(os.path.basename(config), data)
        # The ConfigMap's configuration, laid over the installed one, finds
        # the installed frames and listens where the probes look.
        text = data[os.path.basename(config)]
        self.assertEqual(strip_comments(text), strip_comments(read("deploy", "config",
                                                                   "server.textproto")),
                         "configmap.yaml's server.textproto differs from "
                         "deploy/config/server.textproto: copy the file into it")
        self.assertEqual(port_of(textproto_field(text, "listen_address")), self.ports.server)
        for d in re.findall(r"directory\s*:\s*\"([^\"]+)\"", re.sub(r"#.*", "", text)):
            full = os.path.normpath(os.path.join(installed(mount["mountPath"]), d))
            self.assertTrue(os.path.isdir(full), f"ConfigMap source {d} -> {full}")

    def test_ports_and_probes(self):
        grpc = next(p for p in self.container["ports"] if p["name"] == "grpc")
        self.assertEqual(grpc["containerPort"], self.ports.server)
        # Mutual TLS: exec probes run the CLI's health check with the
        # Secret's client certificate on the server's port.
        for probe in ("startupProbe", "readinessProbe", "livenessProbe"):
            argv = self.container[probe]["exec"]["command"]
            self.check_command(argv, f"deployment.yaml {probe}")
            self.assertEqual(port_of(flag_value(argv, "server")), self.ports.server, probe)
            for flag in ("tls_ca", "tls_cert", "tls_key"):
                self.assertTrue(flag_value(argv, flag).startswith("/etc/cornerpose/tls/"), probe)
        service = self.docs[("Service", "cornerpose-perception")]
        self.assertEqual(service["spec"]["clusterIP"], "None", "headless, for per-call balancing")
        sp = service["spec"]["ports"][0]
        self.assertEqual(sp["port"], self.ports.server)
        self.assertIn(sp["targetPort"], ("grpc", self.ports.server))

    def test_selectors(self):
        labels = self.deployment["spec"]["template"]["metadata"]["labels"]
        for key, value in self.deployment["spec"]["selector"]["matchLabels"].items():
            self.assertEqual(labels.get(key), value)
        for kind in ("Service", "PodDisruptionBudget"):
            doc = next(d for (k, _), d in self.docs.items() if k == kind)
            sel = doc["spec"]["selector"]
            sel = sel.get("matchLabels", sel)
            for key, value in sel.items():
                self.assertEqual(labels.get(key), value, kind)
        hpa = self.docs[("HorizontalPodAutoscaler", "cornerpose-perception")]
        target = hpa["spec"]["scaleTargetRef"]
        self.assertEqual((target["kind"], target["name"]),
                         ("Deployment", self.deployment["metadata"]["name"]))
        self.assertLessEqual(hpa["spec"]["minReplicas"], hpa["spec"]["maxReplicas"])
        self.assertGreater(hpa["spec"]["minReplicas"], 1)

    def test_resources_follow_concurrency(self):
        # Each detection runs on the detector's 2 threads; a replica runs
        # max_concurrent_detections of them at once.
        text = self.configmap_config()["server.textproto"]
        concurrent = int(textproto_field(text, "max_concurrent_detections") or 2)
        res = self.container["resources"]
        cores = lambda q: float(q[:-1]) / 1000 if str(q).endswith("m") else float(q)
        self.assertGreaterEqual(cores(res["requests"]["cpu"]), 2)
        self.assertEqual(cores(res["limits"]["cpu"]), 2 * concurrent)
        # Memory follows the admission limits (see deployment.yaml).
        field = lambda name, default: int(textproto_field(text, name) or default)
        mib = lambda q: int(str(q)[:-2]) * (1024 if str(q).endswith("Gi") else 1)
        # A source keeps its last 6 frames (FrameSource::GrabAfter): 30 MiB of VGA.
        sources = text.count("sources {")
        need = (128 + (2 * concurrent + field("max_queued_detections", 8)) *
                field("max_message_bytes", 67108864) / 2**20 + field("max_streams", 16) * 8 +
                sources * 30)
        self.assertGreaterEqual(mib(res["limits"]["memory"]), need)

    def test_tls_and_reflection_off(self):
        cmd = self.container["command"] + self.container.get("args", [])
        self.assertEqual(flag_value(cmd, "reflection"), "false")
        tls = next(v for v in self.pod["volumes"] if v["name"] == "tls")
        mount = next(m for m in self.container["volumeMounts"] if m["name"] == "tls")
        for flag in ("tls_cert", "tls_key", "tls_client_ca"):
            self.assertEqual(os.path.dirname(flag_value(cmd, flag)), mount["mountPath"], flag)
        self.assertIn("secretName", tls["secret"])
        policy = self.docs[("NetworkPolicy", "cornerpose-perception")]
        self.assertEqual(policy["spec"]["podSelector"]["matchLabels"],
                         self.deployment["spec"]["selector"]["matchLabels"])
        ports = [[p["port"] for p in rule["ports"]] for rule in policy["spec"]["ingress"]]
        http = next(p["containerPort"] for p in self.container["ports"] if p["name"] == "http")
        # gRPC from the clients; the web view and /metrics from them and a scraper.
        self.assertEqual(ports, [[self.ports.server], [http]])
        scraper = policy["spec"]["ingress"][1]["from"]
        self.assertIn({"cornerpose.io/metrics-scraper": "true"},
                      [peer.get("podSelector", {}).get("matchLabels") for peer in scraper])

    def test_user_matches_image(self):
        users = [l.split()[1] for l in read("docker", "Dockerfile").splitlines()
                 if l.startswith("USER ")]
        uid = int(users[-1].split(":")[0])
        sc = self.pod["securityContext"]
        self.assertTrue(sc["runAsNonRoot"])
        self.assertEqual(sc["runAsUser"], uid)


class SystemdTest(DeployTestCase):

    UNIT = ("deploy", "systemd", "cornerpose-robot-client.service")

    def setUp(self):
        parser = configparser.ConfigParser(strict=False, interpolation=None)
        parser.optionxform = str
        parser.read(src(*self.UNIT))
        self.service = parser["Service"]

    def test_exec_start(self):
        argv = shlex.split(self.service["ExecStart"])
        self.assertEqual(argv[0], f"{PREFIX}/bin/cornerpose_robot_client")
        self.check_command(argv, "cornerpose-robot-client.service")
        config = flag_value(argv, "config")
        self.assertTrue(config.startswith("/etc/cornerpose/"), config)
        self.assertTrue(os.path.isfile(src("deploy", "config", os.path.basename(config))),
                        f"{config} is not a shipped configuration")

    def test_restart_and_user(self):
        self.assertEqual(self.service["Restart"], "on-failure")
        self.assertNotIn(self.service.get("User", "root"), ("root", "0"))

    def test_systemd_analyze_verify(self):
        tool = shutil.which("systemd-analyze")
        binary = installed(f"{PREFIX}/bin/cornerpose_robot_client")
        if tool is None:
            self.skipTest("systemd-analyze not installed")
        if not os.access(binary, os.X_OK):
            self.skipTest("cornerpose_robot_client not built")
        with open(src(*self.UNIT)) as f:
            text = f.read().replace(f"{PREFIX}/bin/", os.path.dirname(binary) + "/")
        path = os.path.join(TMP.name, os.path.basename(self.UNIT[-1]))
        with open(path, "w") as f:
            f.write(text)
        out = subprocess.run([tool, "verify", path], capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stdout + out.stderr)


def setUpModule():
    global TMP
    TMP = tempfile.TemporaryDirectory(prefix="cornerpose-deploy-test.")
    out = subprocess.run(["cmake", "--install", BUILD_DIR, "--prefix",
                          os.path.join(TMP.name, PREFIX.lstrip("/"))],
                         capture_output=True, text=True, timeout=300)
    if out.returncode != 0:
        raise RuntimeError(f"cmake --install {BUILD_DIR} failed (build every target first):\n"
                           f"{out.stdout[-2000:]}{out.stderr[-2000:]}")


def tearDownModule():
    TMP.cleanup()


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    SOURCE_DIR, BUILD_DIR = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    unittest.main(argv=[sys.argv[0], *sys.argv[3:]], verbosity=2)
