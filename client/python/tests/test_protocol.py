"""The client's side of the protocol against an in-process fake Labeler: retries on
RESOURCE_EXHAUSTED, reassembly of out-of-order chunks, and answers that break the protocol
(overlapping, short, no summary) reported as DATA_LOSS, never patched over."""

from __future__ import annotations

import time
import warnings
from concurrent import futures
from pathlib import Path

import grpc
import numpy as np
import pytest

import primlabel
from primlabel.v1 import labeling_pb2, labeling_pb2_grpc, model_pb2

CLASSES = [model_pb2.PrimitiveClass(id=1, name="plane"), model_pb2.PrimitiveClass(id=6, name="corner")]


V = labeling_pb2.Vec3d
# What a table-top answer with primitives carries (the fake's "instances" summary).
INSTANCES = labeling_pb2.LabelSummary(
    primitives=[
        labeling_pb2.Primitive(
            segment_id=0, kind=labeling_pb2.PRIMITIVE_PLANE, class_id=1, point_count=900,
            first_point=3, inliers=880, rms=0.002, confidence=0.9, centroid=V(x=0.1, y=0.2, z=0),
            bounds_min=V(x=-1, y=-1, z=-0.01), bounds_max=V(x=1, y=1, z=0.01),
            plane=labeling_pb2.PlaneModel(normal=V(z=1), offset=-0.5, center=V(x=0.1, y=0.2),
                                          axis_u=V(x=1), axis_v=V(y=1), extent_u=2, extent_v=1.5)),
        labeling_pb2.Primitive(
            segment_id=1, kind=labeling_pb2.PRIMITIVE_CYLINDER, class_id=2, point_count=40,
            cylinder=labeling_pb2.CylinderModel(center=V(x=0.3, y=0.1, z=0.6), axis=V(z=1),
                                                radius=0.04, height=0.2)),
        labeling_pb2.Primitive(segment_id=2, kind=labeling_pb2.PRIMITIVE_SEGMENT, class_id=6,
                               point_count=7),
    ],
    table=labeling_pb2.TabletopTable(normal=V(z=1), offset=-0.5, point_count=900,
                                     hull=[V(x=-1, y=-1, z=0.5), V(x=1, y=-1, z=0.5),
                                           V(x=1, y=1, z=0.5)], primitive_ids=[0]),
    objects=[labeling_pb2.TabletopObject(object_id=1, point_count=40, centroid=V(x=0.3, y=0.1,
                                         z=0.6), bounds_min=V(x=0.26, y=0.06, z=0.5),
                                         bounds_max=V(x=0.34, y=0.14, z=0.7), height=0.2,
                                         primitive_ids=[1])],
    class_counts=[labeling_pb2.ClassCount(class_id=2, name="cylinder-convex", points=40)],
)


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
            yield labeling_pb2.LabelResponse(summary=summary_for(header, n))

    def LabelCloud(self, request, context):
        self.calls += 1
        labels = expected_labels(np.frombuffer(request.points.xyz, "<f4").reshape(-1, 3))
        return labeling_pb2.LabelCloudResponse(
            result=labeling_pb2.LabelChunk(point_count=len(labels),
                                           labels=labels.astype("<u4").tobytes()),
            summary=summary_for(request.header, len(labels)))


def summary_for(header, n: int):
    summary = labeling_pb2.LabelSummary(scan_id=header.scan_id, points_received=n,
                                        classes=CLASSES, model="fake")
    if header.scan_id == "out-of-domain":
        summary.domain_warning = "an organised 60x50 frame, trained on scans"
    if header.scan_id == "instances":
        summary.MergeFrom(INSTANCES)
    return summary


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


def test_probability_field_names_as_the_shared_cases_say():
    """The cases tests/client/test_client_cli.cpp checks against the C++ spelling."""
    cases = Path(__file__).resolve().parents[3] / "tests/data/probability_field_names.tsv"
    checked = 0
    for line in cases.read_text(encoding="utf-8").splitlines():
        if not line or line.startswith("#"):
            continue
        name, class_id, expected = line.split("\t")
        assert primlabel.probability_field_name(name, int(class_id)) == expected, line
        checked += 1
    assert checked >= 5


def test_chunks_in_any_order_are_put_back_by_first_point(fake):
    client, _ = fake
    xyz = points(4321)
    result = client.label(xyz, probabilities=True, chunk_points=1500)
    np.testing.assert_array_equal(result.labels, expected_labels(xyz.astype(np.float32)))
    assert [(c.id, c.name) for c in result.model_classes] == [(1, "plane"), (6, "corner")]
    np.testing.assert_array_equal(result.class_ids[result.probabilities.argmax(axis=1)],
                                  result.labels)


def test_classes_name_every_label_by_its_id(fake):
    # The model's classes are 1 and 6 (a subset of the taxonomy), and 0 is every model's
    # "unknown": classes[label] names any label, model_classes are the probabilities' columns.
    client, _ = fake
    xyz = points(100)
    xyz[:3] = np.nan
    result = client.label(xyz, probabilities=True)
    assert result.classes == {0: primlabel.ClassInfo(0, "unknown"),
                              1: primlabel.ClassInfo(1, "plane"),
                              6: primlabel.ClassInfo(6, "corner")}
    assert result.classes[0] is primlabel.UNKNOWN_CLASS
    labels = np.concatenate([[0], result.labels])  # a dropped point's 0 as well
    names = [result.classes[label].name for label in labels]
    assert names[0] == "unknown" and set(names[1:]) == {"plane", "corner"}
    assert list(result.probability_fields()) == ["prob_plane", "prob_corner"]
    assert result.probabilities.shape == (100, len(result.model_classes))


def test_a_domain_warning_is_a_python_warning_and_on_the_result(fake):
    client, _ = fake
    for call in (client.label, client.label_unary):
        with pytest.warns(primlabel.DomainWarning, match="organised 60x50 frame") as caught:
            result = call(points(10), scan_id="out-of-domain")
        assert len(caught) == 1 and caught[0].filename == __file__  # points at the caller
        assert str(caught[0].message) == "model fake: an organised 60x50 frame, trained on scans"
        assert result.domain_warning == "an organised 60x50 frame, trained on scans"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert client.label(points(10)).domain_warning == ""


def test_instances_are_typed_with_their_messages(fake):
    client, _ = fake
    result = client.label(points(1000), scan_id="instances")
    plane, cylinder, segment = result.primitives
    assert isinstance(plane, primlabel.Primitive) and plane.kind == "plane"
    assert (plane.segment_id, plane.class_id, plane.class_name) == (0, 1, "plane")
    assert (plane.point_count, plane.first_point, plane.inliers) == (900, 3, 880)
    assert (plane.rms, plane.confidence) == (0.002, 0.9)
    assert isinstance(plane.model, primlabel.Plane)
    np.testing.assert_array_equal(plane.model.normal, [0, 0, 1])
    np.testing.assert_array_equal(plane.model.coefficients, [0, 0, 1, -0.5])
    assert (plane.model.extent_u, plane.model.extent_v) == (2, 1.5)
    np.testing.assert_array_equal(plane.centroid, [0.1, 0.2, 0])
    np.testing.assert_array_equal(plane.bounds_max - plane.bounds_min, [2, 2, 0.02])
    assert plane.message == result.summary.primitives[0]
    assert cylinder.kind == "cylinder" and cylinder.class_name == "cylinder-convex"
    assert cylinder.parameters.keys() == {"center", "axis", "radius", "height"}
    assert cylinder.model.radius == 0.04
    np.testing.assert_array_equal(cylinder.parameters["center"], [0.3, 0.1, 0.6])
    assert (segment.kind, segment.model, segment.parameters) == ("segment", None, {})
    assert segment.class_name == "corner"
    with pytest.raises(AttributeError):  # frozen
        plane.kind = "sphere"
    with pytest.raises(ValueError):  # and so are its vectors
        plane.centroid[0] = 5

    table = result.table
    assert isinstance(table, primlabel.TabletopTable)
    np.testing.assert_array_equal(table.normal, [0, 0, 1])
    assert table.offset == -0.5 and table.point_count == 900 and table.primitive_ids == (0,)
    assert table.hull.shape == (3, 3) and table.hull.dtype == np.float64
    np.testing.assert_allclose(table.height_of([[0, 0, 0.7], [1, 2, 0.5]]), [0.2, 0])
    assert table.message == result.summary.table
    (obj,) = result.objects
    assert isinstance(obj, primlabel.TabletopObject)
    assert (obj.object_id, obj.point_count, obj.height, obj.primitive_ids) == (1, 40, 0.2, (1,))
    np.testing.assert_allclose(obj.extent, [0.08, 0.08, 0.2])
    np.testing.assert_array_equal(obj.centroid, [0.3, 0.1, 0.6])
    assert obj.message == result.summary.objects[0]
    assert "message" not in repr(obj)
    # Every class a label or a primitive names is in classes, with the server's name for it.
    assert result.classes[2] == primlabel.ClassInfo(2, "cylinder-convex")

    nothing = client.label(points(10))
    assert (nothing.primitives, nothing.objects, nothing.table) == ([], [], None)
    unary = client.label_unary(points(10), scan_id="instances")
    assert [p.kind for p in unary.primitives] == ["plane", "cylinder", "segment"]


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
