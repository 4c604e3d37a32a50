"""The client's TLS options (ca, cert, key) over real TLS handshakes.

cornerpose_server has no TLS port yet (issue 11 adds it), so the peer here is
a gRPC TLS server in this process that requires client certificates and
answers the standard health check; certificates are made at test time with
openssl. When the server gains TLS, the same checks belong against it.
"""

import concurrent.futures
import subprocess

import grpc
import pytest

import cornerpose
from cornerpose._stubs import health_pb2, health_pb2_grpc


def openssl(*args, cwd):
    subprocess.run(["openssl", *args], cwd=cwd, check=True, capture_output=True, timeout=60)


def make_ca(d, name):
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj", f"/CN={name}",
            "-keyout", f"{name}.key", "-out", f"{name}.pem", cwd=d)


def make_cert(d, ca, name, san):
    openssl("req", "-new", "-newkey", "rsa:2048", "-nodes", "-subj", f"/CN={name}",
            "-addext", f"subjectAltName={san}", "-keyout", f"{name}.key", "-out", f"{name}.csr",
            cwd=d)
    openssl("x509", "-req", "-in", f"{name}.csr", "-CA", f"{ca}.pem", "-CAkey", f"{ca}.key",
            "-CAcreateserial", "-days", "2", "-copy_extensions", "copy", "-out", f"{name}.pem",
            cwd=d)


class Serving(health_pb2_grpc.HealthServicer):
    def Check(self, request, context):
        return health_pb2.HealthCheckResponse(status=health_pb2.HealthCheckResponse.SERVING)


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    d = tmp_path_factory.mktemp("pki")
    make_ca(d, "ca")
    make_ca(d, "other_ca")
    make_cert(d, "ca", "server", "DNS:localhost")
    make_cert(d, "ca", "client", "DNS:client")
    make_cert(d, "other_ca", "stranger", "DNS:stranger")
    return d


@pytest.fixture(scope="module")
def tls_server(pki):
    server = grpc.server(concurrent.futures.ThreadPoolExecutor(max_workers=2))
    health_pb2_grpc.add_HealthServicer_to_server(Serving(), server)
    credentials = grpc.ssl_server_credentials(
        [((pki / "server.key").read_bytes(), (pki / "server.pem").read_bytes())],
        root_certificates=(pki / "ca.pem").read_bytes(), require_client_auth=True)
    port = server.add_secure_port("127.0.0.1:0", credentials)
    server.start()
    yield f"localhost:{port}"
    server.stop(grace=None)


def refused(client):
    with client:
        with pytest.raises(cornerpose.CornerposeError) as e:
            client.health()
    return e.value.code in ("UNAVAILABLE", "DEADLINE_EXCEEDED")


def test_mutual_tls_with_valid_certificate(tls_server, pki):
    with cornerpose.Client(tls_server, ca=pki / "ca.pem", cert=pki / "client.pem",
                           key=pki / "client.key", timeout=10) as c:
        assert c.health() == "SERVING"
    # PEM bytes work as well as paths.
    with cornerpose.Client(tls_server, ca=(pki / "ca.pem").read_bytes(),
                           cert=(pki / "client.pem").read_bytes(),
                           key=(pki / "client.key").read_bytes(), timeout=10) as c:
        assert c.health() == "SERVING"


def test_server_name_override(tls_server, pki):
    # The certificate names localhost only: by IP address the name check fails,
    # unless the client is told which name to check.
    address = tls_server.replace("localhost", "127.0.0.1")
    files = dict(ca=pki / "ca.pem", cert=pki / "client.pem", key=pki / "client.key")
    assert refused(cornerpose.Client(address, timeout=3, **files))
    with cornerpose.Client(address, server_name="localhost", timeout=10, **files) as c:
        assert c.health() == "SERVING"


def test_refused_without_client_certificate(tls_server, pki):
    assert refused(cornerpose.Client(tls_server, ca=pki / "ca.pem", timeout=3))


def test_refused_with_certificate_of_another_ca(tls_server, pki):
    assert refused(cornerpose.Client(tls_server, ca=pki / "ca.pem", cert=pki / "stranger.pem",
                                     key=pki / "stranger.key", timeout=3))


def test_refused_when_the_server_is_not_trusted(tls_server, pki):
    assert refused(cornerpose.Client(tls_server, ca=pki / "other_ca.pem", cert=pki / "client.pem",
                                     key=pki / "client.key", timeout=3))


def test_plaintext_to_a_tls_port_fails(tls_server):
    assert refused(cornerpose.Client(tls_server, timeout=3))


def test_bad_tls_arguments(pki, tmp_path):
    with pytest.raises(ValueError, match="both cert and key"):
        cornerpose.Client("localhost:1", cert=pki / "client.pem")
    with pytest.raises(ValueError, match="cannot read"):
        cornerpose.Client("localhost:1", ca=tmp_path / "missing.pem")
