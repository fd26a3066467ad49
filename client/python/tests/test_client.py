"""The Python client against a real primlabel-server: the same labels as the C++ CLI point for
point, streaming in chunks, probabilities and descriptors, errors with their gRPC codes."""

from __future__ import annotations

import socket

import grpc
import numpy as np
import pytest

import primlabel
from conftest import TEST_DATA, TOKEN, binary, run


@pytest.fixture(scope="session")
def cli_labels(server, scan, work):
    """What the C++ CLI writes for the scan: its labels and probabilities."""
    out = work / "cli_labeled.pcd"
    run(binary("primlabel"), "--server", server.address, "label", scan, "-o", out,
        "--probabilities")
    return primlabel.pcd.read(out)


@pytest.fixture(scope="session")
def cli_every_point(server, scan, work):
    """The CLI's labels and probabilities with --every-point (no plane cascade)."""
    out = work / "cli_every_point.pcd"
    run(binary("primlabel"), "--server", server.address, "label", scan, "-o", out,
        "--probabilities", "--every-point")
    return primlabel.pcd.read(out)


@pytest.fixture(scope="session")
def cloud(scan):
    return primlabel.pcd.read(scan)


def test_health_and_models(client):
    assert client.health() == primlabel.HealthStatus.SERVING
    models = client.models()
    assert [(m.name, m.version, m.is_default) for m in models] == [("tiny", "1", True)]
    metadata = client.model_metadata("tiny")
    assert metadata.name == "tiny" and len(metadata.classes) > 1


def test_labels_equal_the_cli_point_for_point(client, cloud, cli_labels):
    # More points than one request message: the default stream has two chunks.
    assert len(cloud) > primlabel.client.DEFAULT_CHUNK_POINTS
    assert cloud.viewpoint[:3] != (0, 0, 0)  # so the viewpoint must be sent
    result = client.label(cloud.xyz, viewpoint=cloud.viewpoint[:3], scan_id="scan")
    assert result.labels.dtype == np.uint32 and result.labels.shape == (len(cloud),)
    np.testing.assert_array_equal(cli_labels.xyz, cloud.xyz)  # C++ and Python readers agree
    np.testing.assert_array_equal(result.labels, cli_labels.label)
    assert result.summary.points_received == len(cloud)
    assert result.summary.scan_id == "scan" and result.summary.model == "tiny"
    assert result.attempts == 1
    # Not a constant answer: the scene has planes, edges and more.
    assert len(np.unique(result.labels)) >= 3
    # Every label, 0 included, is a key of classes.
    assert all(label in result.classes for label in np.unique(result.labels))
    assert result.classes[0].name == "unknown"


def test_the_plane_cascade_by_default_and_every_point(client, cloud, cli_labels, cli_every_point):
    # The tiny model recorded its training scan's noise: the server labels most of the table
    # plane without describing it, unless every_point asks for every point to be described.
    cascaded = client.label(cloud)
    assert cascaded.summary.cascaded_points > len(cloud) // 10
    np.testing.assert_array_equal(cascaded.labels, cli_labels.label)
    exact = client.label(cloud, every_point=True)
    assert exact.summary.cascaded_points == 0
    np.testing.assert_array_equal(exact.labels, cli_every_point.label)
    # The cascade's points are labeled plane, as the model itself labels nearly all of them.
    assert (cascaded.labels != exact.labels).mean() < 0.05


def test_small_chunks_each_way_give_the_same_labels(client, cloud, cli_labels):
    result = client.label(cloud, chunk_points=7777, response_chunk_points=5000)
    np.testing.assert_array_equal(result.labels, cli_labels.label)


def test_float64_input_is_sent_as_float32(client, cloud, cli_labels):
    result = client.label(cloud.xyz.astype(np.float64), viewpoint=cloud.viewpoint[:3])
    np.testing.assert_array_equal(result.labels, cli_labels.label)


def test_probability_rows_sum_to_one_in_the_order_of_classes(client, cloud, cli_every_point):
    # Descriptors describe every point: the server's plane cascade stands aside, as the CLI's
    # --every-point has it.
    result = client.label(cloud, probabilities=True, descriptors=True)
    assert result.summary.cascaded_points == 0
    names = [c.name for c in client.model_metadata("tiny").classes]
    assert [c.name for c in result.model_classes] == names
    assert result.probabilities.shape == (len(cloud), len(result.model_classes))
    # classes: the model's and 0 (unknown), by id, so every label has its name.
    assert list(result.classes.values()) == [primlabel.UNKNOWN_CLASS, *result.model_classes]
    assert {result.classes[label].name for label in result.labels} <= {"unknown", *names}
    described = result.labels != 0
    assert described.mean() > 0.99
    rows = result.probabilities[described]
    np.testing.assert_allclose(rows.sum(axis=1), 1.0, atol=1e-5)
    # A node-only model labels each point with its most probable class: the columns really are
    # the classes in the summary's order.
    np.testing.assert_array_equal(result.class_ids[rows.argmax(axis=1)],
                                  result.labels[described])
    for name, column in result.probability_fields().items():  # the CLI's file names them alike
        np.testing.assert_allclose(column, cli_every_point.fields[name], atol=0)
    assert result.descriptors.shape == (len(cloud), result.summary.descriptor_dim)
    assert result.summary.descriptor_dim == 33
    # Points without a descriptor are the ones labeled unknown.
    np.testing.assert_array_equal(np.isnan(result.descriptors).any(axis=1), ~described)


def test_unary_call_gives_the_streamed_answer(client, cloud, cli_labels):
    result = client.label_unary(cloud, probabilities=True, scan_id="one-message")
    np.testing.assert_array_equal(result.labels, cli_labels.label)
    for name, column in result.probability_fields().items():
        np.testing.assert_allclose(column, cli_labels.fields[name], atol=0)
    assert result.summary.scan_id == "one-message" and result.summary.points_received == len(cloud)
    with pytest.raises(primlabel.InvalidInput):
        client.label_unary(cloud, chunk_points=100)
    with pytest.raises(primlabel.PrimlabelError) as error:
        client.label_unary(cloud.xyz[:100], model="no-such-model")
    assert error.value.code == grpc.StatusCode.NOT_FOUND


@pytest.mark.parametrize("call", ["label", "label_unary"])
def test_primitives_come_with_their_segments(client, cloud, call):
    result = getattr(client, call)(cloud, primitives=True)
    segments, primitives = result.segments, result.primitives
    assert segments.shape == (len(cloud),) and segments.dtype == np.uint32
    assert len(primitives) > 1
    in_segment = segments != primlabel.NO_SEGMENT
    assert in_segment.mean() > 0.5
    assert int(segments[in_segment].max()) < len(primitives)
    sizes = np.bincount(segments[in_segment], minlength=len(primitives))
    for s, primitive in enumerate(primitives):
        assert primitive.segment_id == s and primitive.point_count == sizes[s]
        members = np.flatnonzero(segments == s)
        assert primitive.first_point == members[0]
        # A segment is points of one class, the primitive's.
        np.testing.assert_array_equal(result.labels[members], primitive.class_id)
    # The scene's table is the largest plane, fitted as z = 0 within millimetres.
    planes = [p for p in primitives if p.kind == "plane"]
    assert all(p.message.WhichOneof("model") == "plane" for p in planes)
    table = max(planes, key=lambda p: p.point_count)
    assert table.class_name == "plane"
    assert abs(abs(table.model.normal[2]) - 1) < 1e-3 and abs(table.model.offset) < 5e-3
    assert client.label(cloud).segments is None  # not asked for: none


@pytest.mark.parametrize("call", ["label", "label_unary"])
def test_objects_come_with_their_per_point_ids(client, cloud, call):
    # The scene is z-up; the service takes "up" from a camera (-y, no orientation is sent): the
    # scene as a camera sees it, rotated +90 degrees about x (x, y, z) -> (x, -z, y).
    rotation = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=np.float64)
    xyz = np.asarray(cloud.xyz, dtype=np.float64) @ rotation.T
    viewpoint = rotation @ np.asarray(cloud.viewpoint[:3], dtype=np.float64)
    result = getattr(client, call)(xyz, viewpoint=viewpoint, tabletop_only=True, objects=True,
                                   primitives=True)
    ids = result.object_ids
    assert ids.shape == (len(cloud),) and ids.dtype == np.uint32
    table = result.table
    assert table is not None, result.summary.no_table_reason
    assert abs(abs(table.normal[1]) - 1) < 0.05 and len(table.hull) >= 3
    assert table.hull.shape[1] == 3 and table.primitive_ids == tuple(table.message.primitive_ids)
    assert table.point_count == np.count_nonzero(ids == 0)
    objects = result.objects
    assert len(objects) >= 1
    named = ids[ids != primlabel.NO_OBJECT]
    assert int(named.max()) <= len(objects)
    # Only the table and the objects are labeled (a few of their points may lack a descriptor).
    assert not np.any((ids == primlabel.NO_OBJECT) & (result.labels != 0))
    assert np.count_nonzero((ids != primlabel.NO_OBJECT) & (result.labels == 0)) < 0.01 * len(ids)
    for k, obj in enumerate(objects, start=1):
        members = np.flatnonzero(ids == k)
        assert obj.object_id == k and obj.point_count == len(members)
        points = xyz.astype(np.float32).astype(np.float64)[members]
        lo, hi = points.min(axis=0), points.max(axis=0)
        np.testing.assert_allclose(obj.bounds_min, lo, atol=1e-6)
        np.testing.assert_allclose(obj.bounds_max, hi, atol=1e-6)
        np.testing.assert_allclose(obj.centroid, points.mean(axis=0), atol=1e-4)
        # Its primitives are segments mostly made of its points.
        for s in obj.primitive_ids:
            in_segment = result.segments == s
            assert np.count_nonzero(in_segment & (ids == k)) * 2 > np.count_nonzero(in_segment)
    assert client.label(xyz, tabletop_only=True).object_ids is None  # not asked for: none
    with pytest.raises(primlabel.InvalidInput):
        client.label(xyz, objects=True)


def test_normals_sent_are_used(client):
    bunny = primlabel.pcd.read(TEST_DATA / "samples/bun0.pcd")
    with_normals = client.label(bunny.xyz, normals=bunny.normals)
    assert with_normals.labels.shape == (397,)
    flipped = client.label(bunny.xyz, normals=-bunny.normals)
    # Convex and concave swap with the normals' side, so the server did take them.
    assert not np.array_equal(with_normals.labels, flipped.labels)


def test_non_finite_points_dropped_or_rejected(client, cloud, cli_labels):
    xyz = cloud.xyz.astype(np.float64)
    bad = np.array([0, 17, len(xyz) - 1])
    xyz[bad[0], 0] = np.nan
    xyz[bad[1], 2] = np.inf
    xyz[bad[2]] = 1e300  # float64 beyond float32: inf on the wire
    result = client.label(xyz)
    assert result.summary.points_dropped_non_finite == 3
    np.testing.assert_array_equal(result.labels[bad], 0)
    with pytest.raises(primlabel.PrimlabelError) as error:
        client.label(xyz, non_finite="reject")
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert error.value.attempts == 1


def test_unknown_model_is_not_found(client, cloud):
    with pytest.raises(primlabel.PrimlabelError) as error:
        client.label(cloud.xyz[:1000], model="no-such-model")
    assert error.value.code == grpc.StatusCode.NOT_FOUND
    assert "no-such-model" in error.value.message
    assert str(error.value).startswith("NOT_FOUND: ")


def test_token_is_required_and_checked(token_server, cloud):
    xyz = cloud.xyz[:2000]
    for token in (None, "wrong-token"):
        with primlabel.Client(token_server.address, token=token) as c:
            with pytest.raises(primlabel.PrimlabelError) as error:
                c.label(xyz)
            assert error.value.code == grpc.StatusCode.UNAUTHENTICATED
            assert error.value.attempts == 1  # not retried
    with primlabel.Client(token_server.address, token=TOKEN) as c:
        assert c.label(xyz).labels.shape == (2000,)
        assert [m.name for m in c.models()] == ["tiny"]


def test_a_cloud_in_millimetres_is_labeled_as_in_metres_with_units(client, cloud, cli_labels):
    millimetres = cloud.xyz.astype(np.float64) * 1000.0
    viewpoint = np.asarray(cloud.viewpoint[:3], dtype=np.float64) * 1000.0
    result = client.label(millimetres, viewpoint=viewpoint, units="mm")
    # float32 round trips through x1000 and x0.001 move a few points by an ulp, no more.
    assert np.mean(result.labels == cli_labels.label) > 0.99
    # Unscaled, the same numbers are a sparse cloud a kilometre wide: nothing is labeled like it.
    raw = client.label(millimetres, viewpoint=viewpoint)
    assert np.mean(raw.labels == cli_labels.label) < 0.5
    with pytest.raises(primlabel.InvalidInput):
        client.label(millimetres, units="inch")


def test_bad_arrays_are_refused_before_any_call(client):
    for xyz in (np.zeros((5, 2)), np.zeros(3), np.array([["a", "b", "c"]]), np.zeros((2, 3), complex)):
        with pytest.raises(ValueError):
            client.label(xyz)
    with pytest.raises(primlabel.InvalidInput):
        client.label(np.zeros((4, 3)), normals=np.zeros((3, 3)))
    with pytest.raises(primlabel.InvalidInput):
        client.label(np.zeros((4, 3)), voxel_size=float("nan"))
    with pytest.raises(primlabel.InvalidInput):
        client.label(np.zeros((4, 3)), chunk_points=0)


def test_empty_cloud_is_answered_cleanly(client):
    try:
        result = client.label(np.zeros((0, 3), np.float32), probabilities=True)
    except primlabel.PrimlabelError as error:  # the server may refuse an empty scan
        assert error.code == grpc.StatusCode.INVALID_ARGUMENT
    else:
        assert result.labels.shape == (0,)
        assert result.probabilities.shape == (0, len(result.model_classes))


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_server_is_retried_then_unavailable():
    policy = primlabel.BackoffPolicy(initial=0.01, maximum=0.05)
    with primlabel.Client(f"127.0.0.1:{free_port()}", retry_attempts=3, backoff=policy,
                          deadline=10) as c:
        with pytest.raises(primlabel.PrimlabelError) as error:
            c.health()
        assert error.value.code == grpc.StatusCode.UNAVAILABLE
        assert error.value.attempts == 3
        assert "(after 3 attempts)" in str(error.value)
