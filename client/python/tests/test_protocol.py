"""The client's side of the protocol against an in-process fake Labeler: retries on
RESOURCE_EXHAUSTED, reassembly of out-of-order chunks, and answers that break the protocol
(overlapping, short, no summary) reported as DATA_LOSS, never patched over."""

from __future__ import annotations

import time
from concurrent import futures

import grpc
import numpy as np
import pytest

import primlabel
from primlabel.v1 import labeling_pb2, labeling_pb2_grpc, model_pb2

CLASSES = [model_pb2.PrimitiveClass(id=1, name="plane"), model_pb2.PrimitiveClass(id=6, name="corner")]


def expected_labels(xyz: np.ndarray) -> np.ndarray:
    """The fake's answer: 6 (corner) where x > 0, else 1 (plane)."""
    return np.where(xyz[:, 0] > 0, 6, 1).astype(np.uint32)


class FakeLabeler(labeling_pb2_grpc.LabelerServicer):
    def __init__(self):
        self.calls = 0

    def Label(self, request_iterator, context):
        self.calls += 1
        header, parts = None, []
        for request in request_iterator:
            if request.HasField("header"):
                header = request.header
            elif request.HasField("chunk"):
                parts.append(np.frombuffer(request.chunk.xyz, "<f4").reshape(-1, 3))
        behaviour = header.scan_id
        while behaviour == "slow" and context.is_active():  # until the client gives up
            time.sleep(0.01)
        if behaviour == "busy-once" and self.calls == 1:
            context.abort(grpc.StatusCode.RESOURCE_EXHAUSTED, "queue full")
        xyz = np.concatenate(parts) if parts else np.zeros((0, 3), np.float32)
        labels = expected_labels(xyz)
        probabilities = np.stack([labels == 1, labels == 6], axis=1).astype("<f4")
        n, step = len(xyz), 1000
        # Chunks in reverse order: the client must place them by first_point.
        firsts = list(range(0, n, step))[::-1]
        if behaviour == "overlap":
            firsts.append(0)
        if behaviour == "short":
            firsts = firsts[1:]
        for first in firsts:
            end = min(first + step, n)
            chunk = labeling_pb2.LabelChunk(first_point=first, point_count=end - first,
                                            labels=labels[first:end].astype("<u4").tobytes())
            if header.options.return_probabilities:
                chunk.probabilities = probabilities[first:end].tobytes()
            yield labeling_pb2.LabelResponse(chunk=chunk)
        if behaviour != "no-summary":
            yield labeling_pb2.LabelResponse(summary=labeling_pb2.LabelSummary(
                scan_id=header.scan_id, points_received=n, classes=CLASSES))


@pytest.fixture()
def fake():
    server = grpc.server(futures.ThreadPoolExecutor(max_workers=2))
    labeler = FakeLabeler()
    labeling_pb2_grpc.add_LabelerServicer_to_server(labeler, server)
    port = server.add_insecure_port("127.0.0.1:0")
    server.start()
    policy = primlabel.BackoffPolicy(initial=0.01, maximum=0.02)
    with primlabel.Client(f"127.0.0.1:{port}", deadline=20, backoff=policy) as client:
        yield client, labeler
    server.stop(grace=None)


def points(n: int) -> np.ndarray:
    return np.random.default_rng(1).uniform(-1, 1, (n, 3))


def test_chunks_in_any_order_are_put_back_by_first_point(fake):
    client, _ = fake
    xyz = points(4321)
    result = client.label(xyz, probabilities=True, chunk_points=1500)
    np.testing.assert_array_equal(result.labels, expected_labels(xyz.astype(np.float32)))
    assert [(c.id, c.name) for c in result.classes] == [(1, "plane"), (6, "corner")]
    np.testing.assert_array_equal(result.class_ids[result.probabilities.argmax(axis=1)],
                                  result.labels)


def test_resource_exhausted_is_retried(fake):
    client, labeler = fake
    xyz = points(2500)
    result = client.label(xyz, scan_id="busy-once")
    assert result.attempts == 2 and labeler.calls == 2
    np.testing.assert_array_equal(result.labels, expected_labels(xyz.astype(np.float32)))


def test_no_retry_when_attempts_are_one(fake):
    client, labeler = fake
    client.retry_attempts = 1
    with pytest.raises(primlabel.PrimlabelError) as error:
        client.label(points(10), scan_id="busy-once")
    assert error.value.code == grpc.StatusCode.RESOURCE_EXHAUSTED
    assert error.value.message == "queue full" and labeler.calls == 1


@pytest.mark.parametrize("behaviour,message", [
    ("overlap", "twice"),
    ("short", "covers 3000 of 3500 points; first missing point 3000"),
    ("no-summary", "without a summary"),
])
def test_broken_answers_are_data_loss(fake, behaviour, message):
    client, labeler = fake
    with pytest.raises(primlabel.PrimlabelError) as error:
        client.label(points(3500), scan_id=behaviour)
    assert error.value.code == grpc.StatusCode.DATA_LOSS
    assert message in error.value.message
    assert labeler.calls == 1  # a broken answer is not retried


def test_backoff_grows_with_jitter_and_is_capped():
    policy = primlabel.BackoffPolicy(initial=0.2, multiplier=2.0, maximum=5.0, jitter=0.2)
    backoff = primlabel.Backoff(policy, seed=7)
    assert [backoff.nominal(n) for n in range(6)] == [0.2, 0.4, 0.8, 1.6, 3.2, 5.0]
    assert backoff.nominal(10_000) == 5.0  # no overflow
    for n in range(8):
        delay = backoff.next()
        centre = min(policy.initial * 2**n, 5.0)  # capped, then jittered, then capped again
        assert centre * 0.8 <= delay <= min(centre * 1.2, 5.0)
    backoff.reset()
    assert 0.16 <= backoff.next() <= 0.24


def test_health_wire_round_trip():
    from primlabel import wire

    assert wire.encode_health_request("") == b""
    assert wire.encode_health_request("primlabel.v1.Labeler") == b"\x0a\x14primlabel.v1.Labeler"
    assert wire.decode_health_status(b"\x08\x01") == 1
    assert wire.decode_health_status(b"") == 0
    with pytest.raises(primlabel.errors.ProtocolError):
        wire.decode_health_status(b"\x08")


def test_the_deadline_ends_a_call_the_server_does_not_answer(fake):
    client, labeler = fake
    with pytest.raises(primlabel.PrimlabelError) as error:
        client.label(points(100), scan_id="slow", deadline=0.3)
    assert error.value.code == grpc.StatusCode.DEADLINE_EXCEEDED
    assert error.value.attempts == 1 and labeler.calls == 1  # not retried
