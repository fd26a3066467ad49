"""The Python client over TLS and mutual TLS to a real primlabel-server, with a CA, a server
certificate for 127.0.0.1 / localhost and a client certificate made by openssl for the test."""

from __future__ import annotations

import shutil
import subprocess

import grpc
import numpy as np
import pytest

import primlabel
from conftest import Server

KEY = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]


def openssl(*arguments, cwd):
    subprocess.run(["openssl", *arguments], cwd=cwd, check=True, capture_output=True, timeout=30)


@pytest.fixture(scope="module")
def certificates(tmp_path_factory):
    if shutil.which("openssl") is None:
        pytest.skip("openssl is not installed")
    d = tmp_path_factory.mktemp("certs")
    (d / "san.ext").write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    openssl("req", "-x509", *KEY, "-keyout", "ca.key", "-out", "ca.pem", "-days", "2", "-subj",
            "/CN=primlabel-test-ca", cwd=d)
    for name in ("server", "client"):
        openssl("req", *KEY, "-keyout", f"{name}.key", "-out", f"{name}.csr", "-subj",
                "/CN=localhost" if name == "server" else "/CN=robot", cwd=d)
        extra = ["-extfile", "san.ext"] if name == "server" else []
        openssl("x509", "-req", "-in", f"{name}.csr", "-CA", "ca.pem", "-CAkey", "ca.key",
                "-CAcreateserial", "-out", f"{name}.pem", "-days", "2", *extra, cwd=d)
    # An unrelated CA: a server certificate it did not sign must be refused.
    openssl("req", "-x509", *KEY, "-keyout", "other.key", "-out", "other.pem", "-days", "2",
            "-subj", "/CN=someone-else", cwd=d)
    return d


@pytest.fixture(scope="module")
def tls_server(models, certificates, work):
    s = Server(models, work / "tls-server.log", "--tls-cert", str(certificates / "server.pem"),
               "--tls-key", str(certificates / "server.key"))
    yield s
    s.stop()


@pytest.fixture(scope="module")
def mtls_server(models, certificates, work):
    s = Server(models, work / "mtls-server.log", "--tls-cert", str(certificates / "server.pem"),
               "--tls-key", str(certificates / "server.key"),
               "--tls-client-ca", str(certificates / "ca.pem"))
    yield s
    s.stop()


def xyz() -> np.ndarray:
    grid = np.stack(np.meshgrid(np.arange(40), np.arange(40)), axis=-1).reshape(-1, 2) * 0.005
    return np.column_stack([grid, np.zeros(len(grid))]).astype(np.float32)


def test_labels_over_tls_with_the_servers_ca(tls_server, certificates):
    tls = primlabel.Tls(ca_file=str(certificates / "ca.pem"))
    with primlabel.Client(tls_server.address, tls=tls, deadline=20) as client:
        assert client.health() == primlabel.HealthStatus.SERVING
        result = client.label(xyz())
    assert result.labels.shape == (1600,) and (result.labels != 0).all()


def test_a_server_the_ca_did_not_sign_is_refused(tls_server, certificates):
    tls = primlabel.Tls(ca_file=str(certificates / "other.pem"))
    with primlabel.Client(tls_server.address, tls=tls, deadline=5, retry_attempts=1) as client:
        with pytest.raises(primlabel.PrimlabelError) as error:
            client.label(xyz())
    assert error.value.code == grpc.StatusCode.UNAVAILABLE


def test_plaintext_to_a_tls_server_fails(tls_server):
    with primlabel.Client(tls_server.address, deadline=5, retry_attempts=1) as client:
        with pytest.raises(primlabel.PrimlabelError) as error:
            client.label(xyz())
    assert error.value.code == grpc.StatusCode.UNAVAILABLE


def test_mutual_tls_needs_the_client_certificate(mtls_server, certificates):
    ca = str(certificates / "ca.pem")
    with primlabel.Client(mtls_server.address, tls=primlabel.Tls(ca_file=ca), deadline=5,
                          retry_attempts=1) as client:
        with pytest.raises(primlabel.PrimlabelError) as error:
            client.label(xyz())
    assert error.value.code == grpc.StatusCode.UNAVAILABLE
    tls = primlabel.Tls(ca_file=ca, cert_file=str(certificates / "client.pem"),
                        key_file=str(certificates / "client.key"))
    with primlabel.Client(mtls_server.address, tls=tls, deadline=20) as client:
        assert client.label(xyz()).labels.shape == (1600,)


def test_half_a_client_identity_is_refused_before_any_call(certificates):
    with pytest.raises(primlabel.InvalidInput):
        primlabel.Client("127.0.0.1:1", tls=primlabel.Tls(
            cert_file=str(certificates / "client.pem")))
    with pytest.raises(primlabel.InvalidInput):
        primlabel.Client("127.0.0.1:1", tls=primlabel.Tls(ca_file="/nonexistent/ca.pem"))
