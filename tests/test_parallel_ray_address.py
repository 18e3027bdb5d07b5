"""benchmark.parallel.check_ray_address: anything that is not a Ray cluster is refused within seconds."""

import socket
import threading
import time

import pytest

from benchmark import parallel
from benchmark.commands.cli import main
from benchmark.parallel import RayAddressError, check_ray_address


def _listener(reply: bytes | None):
    """A loopback TCP server that answers every connection with ``reply`` (None: reads and says nothing)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    stop = threading.Event()

    def serve():
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            with conn:
                conn.settimeout(8)
                try:
                    conn.recv(64)
                    if reply is not None:
                        conn.sendall(reply)
                    else:
                        stop.wait(8)
                except OSError:
                    pass

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return server, stop


@pytest.mark.parametrize("reply", [b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n", b"", None],
                         ids=["http", "closes", "silent"])
def test_a_service_that_is_not_ray_is_refused_within_seconds(tmp_path, capsys, monkeypatch, reply):
    pytest.importorskip("ray")
    monkeypatch.setattr(parallel, "RAY_CONNECT_TIMEOUT_S", 1.0)  # the silent service is waited for this long
    server, stop = _listener(reply)
    try:
        address = f"127.0.0.1:{server.getsockname()[1]}"
        t0 = time.perf_counter()
        code = main(["eval", "--suite", "smoke", "--out", str(tmp_path / "o"), "--cache", str(tmp_path / "c"),
                     "--ray-address", address])
        assert code == 2 and time.perf_counter() - t0 < 10
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"'{address}': something listens there but it is not a Ray cluster" in err
        assert "(no gRPC answer within 1 s)" in err
        assert not (tmp_path / "o").exists() and not (tmp_path / "c").exists()
    finally:
        stop.set()
        server.close()


def test_auto_without_a_cluster_exits_2_and_writes_nothing(tmp_path, capsys, monkeypatch):
    services = pytest.importorskip("ray._private.services")
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setattr(services, "find_gcs_addresses", lambda: [])  # this machine runs no cluster
    monkeypatch.setattr(services, "find_bootstrap_address", lambda temp_dir: None)
    t0 = time.perf_counter()
    code = main(["generate", "--out", str(tmp_path / "d"), "--tasks", "lift", "--seeds", "0", "--ray-address", "auto"])
    assert code == 2 and time.perf_counter() - t0 < 10
    assert "--ray-address auto: no Ray cluster runs on this machine" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


def test_a_real_cluster_passes_the_check(ray_cluster):
    check_ray_address(ray_cluster)
    with pytest.raises(RayAddressError, match="expected 'auto', 'host:port'"):
        check_ray_address("nowhere")
