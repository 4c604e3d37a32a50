"""Build step of the cornerpose client: generates the gRPC stubs.

The package's own code is in src/cornerpose/; its protobuf and gRPC modules
are generated from the repository's proto/ directory into the build tree
whenever the package is built (pip install, python -m build), so they always
match the API they are built against and are never committed:

  cornerpose/v1/*_pb2.py, *_pb2_grpc.py   from proto/cornerpose/v1/*.proto
  cornerpose/_health/health_pb2*.py        from proto/grpc/health/v1/health.proto

Tools, in order of preference (override with the environment variables):
  PROTOC              protoc (Debian: protobuf-compiler; 3.15 or newer for
                      proto3 `optional`)
  GRPC_PYTHON_PLUGIN  grpc_python_plugin (Debian: protobuf-compiler-grpc)
  CORNERPOSE_PROTO_DIR  the proto/ directory (default: ../../proto)
"""

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = pathlib.Path(__file__).resolve().parent


def proto_dir() -> pathlib.Path:
    path = pathlib.Path(os.environ.get("CORNERPOSE_PROTO_DIR", HERE.parent.parent / "proto"))
    if not (path / "cornerpose" / "v1" / "perception_service.proto").is_file():
        sys.exit(f"cornerpose-client: no cornerpose/v1/perception_service.proto under {path}; "
                 "build from the repository checkout or set CORNERPOSE_PROTO_DIR")
    return path


def find_tool(env: str, name: str, debian_package: str) -> str:
    tool = os.environ.get(env) or shutil.which(name)
    if not tool:
        sys.exit(f"cornerpose-client: {name} not found (Debian: apt-get install {debian_package}, "
                 f"or set {env})")
    return tool


def run_protoc(include: pathlib.Path, files, out: pathlib.Path) -> None:
    protoc = find_tool("PROTOC", "protoc", "protobuf-compiler")
    plugin = find_tool("GRPC_PYTHON_PLUGIN", "grpc_python_plugin", "protobuf-compiler-grpc")
    cmd = [protoc, f"--proto_path={include}", f"--python_out={out}", f"--grpc_python_out={out}",
           f"--plugin=protoc-gen-grpc_python={plugin}", *[str(f) for f in files]]
    result = subprocess.run(cmd, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"cornerpose-client: protoc failed ({' '.join(cmd)}):\n{result.stderr}")


def generate(out: pathlib.Path) -> None:
    protos = proto_dir()
    api = sorted((protos / "cornerpose" / "v1").glob("*.proto"))
    run_protoc(protos, api, out)
    (out / "cornerpose" / "v1" / "__init__.py").write_text('"""Generated from proto/cornerpose/v1."""\n')
    # gRPC's health protocol, moved under cornerpose/_health so its modules
    # cannot shadow the grpc package (the wire names stay grpc.health.v1).
    with tempfile.TemporaryDirectory() as tmp:
        moved = pathlib.Path(tmp) / "cornerpose" / "_health" / "health.proto"
        moved.parent.mkdir(parents=True)
        shutil.copy(protos / "grpc" / "health" / "v1" / "health.proto", moved)
        run_protoc(pathlib.Path(tmp), [moved], out)
    (out / "cornerpose" / "_health" / "__init__.py").write_text(
        '"""Generated from proto/grpc/health/v1/health.proto."""\n')


class BuildPyWithStubs(build_py):
    """build_py, then the generated modules into the same build directory."""

    def run(self):
        super().run()
        generate(pathlib.Path(self.build_lib))


setup(cmdclass={"build_py": BuildPyWithStubs})
