"""How the server chose the model (Result.model_choice) and the DomainWarning a named model
used outside its domain raises; organised frames, as (H, W, 3) arrays or organised PointClouds,
are sent with their width and height."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import primlabel


@pytest.fixture(scope="module")
def cloud(scan):
    return primlabel.pcd.read(scan)


def test_a_named_model_is_named_and_an_only_model_is_the_default(client, cloud):
    named = client.label(cloud.xyz[:3000], model="tiny")
    assert (named.model_choice, named.model_choice_reason) == ("named", "named by the request")
    unnamed = client.label(cloud.xyz[:3000])
    assert unnamed.summary.model == "tiny"
    assert unnamed.model_choice == "default"
    assert unnamed.model_choice_reason == "the only model served"


def test_a_frame_sent_to_a_scanner_model_warns(client, cloud):
    # tiny was trained on unorganised LMS400 scans: an organised frame is outside its domain.
    frame = cloud.xyz[:3000].reshape(50, 60, 3)
    with pytest.warns(primlabel.DomainWarning, match="organised 60x50 frame"):
        result = client.label(frame, model="tiny")
    assert result.labels.shape == (3000,)
    organised = primlabel.pcd.PointCloud(xyz=cloud.xyz[:3000], width=60, height=50)
    with pytest.warns(primlabel.DomainWarning, match="organised 60x50 frame"):
        client.label_unary(organised, model="tiny")


def test_an_unorganised_cloud_in_its_domain_does_not_warn(client, cloud):
    with warnings.catch_warnings():
        warnings.simplefilter("error", primlabel.DomainWarning)
        result = client.label(cloud.xyz, model="tiny")
    assert result.summary.domain_warning == ""


def test_a_frame_whose_size_does_not_match_its_points_is_refused(client, cloud):
    bad = primlabel.pcd.PointCloud(xyz=cloud.xyz[:3000], width=70, height=50)
    with pytest.raises(primlabel.PrimlabelError) as error:
        client.label(bad, model="tiny")
    assert "layout.width x layout.height" in error.value.message


def test_shape_sends_a_flat_clouds_frame_size(client, cloud):
    # An Open3D cloud of a frame is flat: shape=(H, W) gives the server its frame size back.
    flat = np.asarray(cloud.xyz[:3000])
    with pytest.warns(primlabel.DomainWarning, match="organised 60x50 frame"):
        client.label(flat, model="tiny", shape=(50, 60))
    with pytest.raises(primlabel.InvalidInput, match="does not hold"):
        client.label(flat, model="tiny", shape=(50, 61))
    with pytest.raises(primlabel.InvalidInput, match="height, width"):
        client.label(flat, model="tiny", shape=50)
