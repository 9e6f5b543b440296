"""Contact clusters: periodic 4-connected labelling, statistics, per-step dataset."""
from collections import deque

import numpy as np
import pytest

from roughcontact.statistics.clusters import (
    cluster_area_histogram,
    cluster_dataset,
    cluster_statistics,
    default_area_bins,
    label_clusters,
)


def disc(n, cx, cy, r):
    """Periodic disc: node distances use the minimum image so it may wrap."""
    i = np.arange(n)
    dx = (i[:, None] - cx + n / 2) % n - n / 2
    dy = (i[None, :] - cy + n / 2) % n - n / 2
    return dx**2 + dy**2 <= r**2


def bfs_labels(mask):
    """Independent reference: periodic flood fill with modulo indexing, 4-connected.

    Seeds are visited in C order, so clusters are numbered by their first node in
    C order -- the numbering label_clusters promises.
    """
    n = mask.shape[0]
    labels = np.zeros(mask.shape, np.int32)
    count = 0
    for i0 in range(n):
        for j0 in range(n):
            if mask[i0, j0] and not labels[i0, j0]:
                count += 1
                labels[i0, j0] = count
                queue = deque([(i0, j0)])
                while queue:
                    i, j = queue.popleft()
                    for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                        a, b = (i + di) % n, (j + dj) % n
                        if mask[a, b] and not labels[a, b]:
                            labels[a, b] = count
                            queue.append((a, b))
    return labels


def bfs_count(mask):
    return int(bfs_labels(mask).max(initial=0))


def assert_valid_labels(labels, count, mask):
    assert labels.dtype == np.int32 and labels.shape == mask.shape
    np.testing.assert_array_equal(labels > 0, mask)
    assert set(np.unique(labels[mask])) == set(range(1, count + 1))
    # Deterministic order: cluster k's first node (C order) precedes cluster k+1's.
    flat = labels.ravel()
    firsts = [np.flatnonzero(flat == k)[0] for k in range(1, count + 1)]
    assert firsts == sorted(firsts)


# --------------------------------------------------------------------------- labelling
def test_single_disc_has_one_cluster_of_its_pixel_area():
    m = disc(32, 15, 16, 5)
    labels, count = label_clusters(m)
    assert count == 1
    assert_valid_labels(labels, count, m)
    st = cluster_statistics(m)
    assert st["areas_pixels"].tolist() == [int(m.sum())]
    assert st["areas"][0] == pytest.approx(m.sum() / 32**2)


def test_two_discs_are_two_clusters():
    m = disc(32, 8, 8, 4) | disc(32, 22, 20, 3)
    labels, count = label_clusters(m)
    assert count == 2
    assert_valid_labels(labels, count, m)
    st = cluster_statistics(m)
    assert st["areas_pixels"].tolist() == sorted([int(disc(32, 8, 8, 4).sum()),
                                                  int(disc(32, 22, 20, 3).sum())], reverse=True)


def test_stripe_through_the_x_boundary_is_one_cluster():
    n = 16
    m = np.zeros((n, n), bool)
    m[0, 3:9] = True
    m[n - 1, 3:9] = True  # only joined through the wrap of axis 0
    labels, count = label_clusters(m)
    assert count == 1
    assert_valid_labels(labels, count, m)


def test_stripe_through_the_y_boundary_is_one_cluster():
    n = 16
    m = np.zeros((n, n), bool)
    m[5:9, 0] = True
    m[5:9, n - 1] = True
    assert label_clusters(m)[1] == 1


def test_blob_split_into_the_four_corners_is_one_cluster():
    m = disc(20, 0, 0, 3)
    assert m[0, 0] and m[-1, -1] and m[0, -1] and m[-1, 0] and not m[10, 10]
    labels, count = label_clusters(m)
    assert count == 1
    assert_valid_labels(labels, count, m)
    assert cluster_statistics(m)["areas_pixels"].tolist() == [int(m.sum())]


def test_corner_only_across_the_wrap_is_two_clusters():
    m = np.zeros((8, 8), bool)
    m[0, 0] = m[-1, -1] = True  # diagonal neighbours on the torus
    assert label_clusters(m)[1] == 2


def test_diagonal_only_neighbours_are_separate_clusters():
    m = np.zeros((6, 6), bool)
    m[1, 1] = m[2, 2] = m[3, 1] = True
    labels, count = label_clusters(m)
    assert count == 3
    assert_valid_labels(labels, count, m)
    checker = (np.add.outer(np.arange(6), np.arange(6)) % 2).astype(bool)
    assert label_clusters(checker)[1] == 18


def test_full_mask_is_one_cluster_of_area_one():
    m = np.ones((9, 9), bool)
    labels, count = label_clusters(m)
    assert count == 1 and np.all(labels == 1)
    st = cluster_statistics(m)
    assert st["count"] == 1 and st["max_area"] == 1.0 and st["mean_area"] == 1.0
    np.testing.assert_array_equal(st["areas"], [1.0])


def test_empty_mask_has_no_cluster_and_no_nan():
    m = np.zeros((10, 10), bool)
    labels, count = label_clusters(m)
    assert count == 0 and not labels.any()
    st = cluster_statistics(m)
    assert st["count"] == 0 and st["mean_area"] == 0.0 and st["max_area"] == 0.0
    assert st["areas"].shape == (0,)
    assert cluster_area_histogram(st["areas_pixels"], 100).sum() == 0


def test_single_node_cell():
    assert label_clusters(np.ones((1, 1), bool))[1] == 1
    assert label_clusters(np.zeros((1, 1), bool))[1] == 0
    st = cluster_statistics(np.ones((1, 1), bool))
    assert cluster_area_histogram(st["areas_pixels"], 1).sum() == 1


def test_labels_are_deterministic_and_ordered_by_first_node():
    rng = np.random.default_rng(3)
    m = rng.random((25, 25)) < 0.45
    l1, c1 = label_clusters(m)
    l2, c2 = label_clusters(m.copy())
    np.testing.assert_array_equal(l1, l2)
    assert c1 == c2
    assert_valid_labels(l1, c1, m)


def test_labels_follow_a_periodic_shift():
    """Rolling the cell permutes labels but keeps the partition."""
    rng = np.random.default_rng(4)
    m = rng.random((21, 21)) < 0.5
    labels, count = label_clusters(m)
    shifted, count_s = label_clusters(np.roll(m, (7, -5), axis=(0, 1)))
    assert count_s == count
    rolled = np.roll(labels, (7, -5), axis=(0, 1))
    pairs = {(a, b) for a, b in zip(rolled[rolled > 0], shifted[shifted > 0], strict=True)}
    assert len(pairs) == count  # a bijection between the two labellings


@pytest.mark.parametrize("n", [7, 13, 16])
@pytest.mark.parametrize("density", [0.3, 0.5, 0.6])
def test_random_masks_match_periodic_bfs(n, density):
    rng = np.random.default_rng(n * 100 + int(density * 10))
    for _ in range(5):
        m = rng.random((n, n)) < density
        labels, count = label_clusters(m)
        assert count == bfs_count(m)
        assert_valid_labels(labels, count, m)
        np.testing.assert_array_equal(labels, bfs_labels(m))  # same partition, same numbering


def test_random_mask_against_the_3x3_tiled_image():
    """On the 3x3 tiling, the central tile's labels (plain, non-periodic ndimage
    labelling) connect exactly as the periodic labels do, for clusters that do not
    wrap onto themselves; count periodic clusters as classes of tiled labels."""
    from scipy import ndimage

    rng = np.random.default_rng(11)
    n = 15
    m = rng.random((n, n)) < 0.35
    labels, count = label_clusters(m)
    tiled, _ = ndimage.label(np.tile(m, (3, 3)))
    # Each periodic cluster maps, node by node, to tiled labels; two nodes in one
    # tiled component must share a periodic label.
    for di in range(3):
        for dj in range(3):
            block = tiled[di * n:(di + 1) * n, dj * n:(dj + 1) * n]
            for t in np.unique(block[block > 0]):
                assert len(np.unique(labels[block == t])) == 1
    assert count == bfs_count(m)


def test_odd_n():
    n = 11
    m = np.zeros((n, n), bool)
    m[0, :] = True  # a full row closes on itself along y
    m[5, 2:4] = True
    m[n - 1, 8] = True  # joins row 0 through the x wrap
    labels, count = label_clusters(m)
    assert count == 2
    assert cluster_statistics(m)["areas_pixels"].tolist() == [n + 1, 2]


# --------------------------------------------------------------------------- statistics
def test_statistics_areas_sum_to_contact_fraction_and_length_scales_physical():
    rng = np.random.default_rng(5)
    m = rng.random((20, 20)) < 0.4
    st = cluster_statistics(m, length=2.0)
    assert st["areas"].sum() == pytest.approx(m.mean())
    assert np.all(np.diff(st["areas"]) <= 0)
    np.testing.assert_allclose(st["areas_physical"], 4.0 * st["areas"])
    assert st["max_area"] == st["areas"][0]
    assert st["mean_area"] == pytest.approx(st["areas"].mean())


def test_histogram_counts_sum_to_count():
    rng = np.random.default_rng(6)
    for n in (8, 17, 32):
        m = rng.random((n, n)) < 0.45
        st = cluster_statistics(m)
        h = cluster_area_histogram(st["areas_pixels"], n * n)
        assert h.dtype == np.int64 and h.shape == (24,)
        assert h.sum() == st["count"]
    # One-node and cell-filling clusters sit exactly on the outer edges.
    assert cluster_area_histogram([1], 33 * 33).tolist()[0] == 1
    assert cluster_area_histogram([33 * 33], 33 * 33).tolist()[-1] == 1


def test_histogram_custom_bins():
    h = cluster_area_histogram([1, 2, 4, 50], 100, bins=[0.01, 0.03, 0.1, 1.0])
    assert h.tolist() == [2, 1, 1]
    edges = default_area_bins(64 * 64)
    assert edges[0] == 1 / 64**2 and edges[-1] == 1.0 and edges.size == 25


# --------------------------------------------------------------------------- dataset
def test_dataset_from_masks_and_pressures():
    n = 16
    empty = np.zeros((n, n))
    p = np.where(disc(n, 0, 0, 3) | disc(n, 8, 8, 2), 1.5, 0.0)
    full = np.ones((n, n), bool)
    ds = cluster_dataset([empty, p, full], steps=[1, 2, 3], length=2.0)
    assert ds.cluster_count.values.tolist() == [0, 2, 1]
    assert ds.cluster_count.dtype == np.int64
    np.testing.assert_allclose(ds.cluster_max_area.values,
                               [0.0, disc(n, 0, 0, 3).sum() / n**2, 1.0])
    assert ds.cluster_mean_area.values[0] == 0.0
    assert not np.isnan(ds.cluster_mean_area.values).any()
    assert ds.cluster_area_histogram.dims == ("step", "area_bin")
    np.testing.assert_array_equal(ds.cluster_area_histogram.sum("area_bin").values,
                                  ds.cluster_count.values)
    np.testing.assert_allclose(ds.area_bin.values,
                               np.sqrt(ds.area_bin_low.values * ds.area_bin_high.values))
    assert ds.area_bin_low.dims == ds.area_bin_high.dims == ("area_bin",)
    for name in list(ds.data_vars) + list(ds.coords):
        assert ds[name].attrs.get("units") and ds[name].attrs.get("long_name"), name
    assert ds.attrs["length"] == 2.0


def test_dataset_accepts_a_3d_array_and_custom_bins():
    rng = np.random.default_rng(8)
    stack = rng.random((2, 9, 9)) - 0.5
    bins = [1 / 81, 0.1, 1.0]
    ds = cluster_dataset(stack, steps=np.array([4, 7]), length=1.0, bins=bins)
    assert ds.sizes == {"step": 2, "area_bin": 2, "connectivity": 2}
    assert ds.step.values.tolist() == [4, 7]
    assert ds.cluster_count.values.tolist() == [bfs_count(s > 0) for s in stack]


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("bad, match", [
    (np.zeros(5, bool), "2-D"),
    (np.zeros((2, 3, 3), bool), "2-D"),
    (np.zeros((4, 5), bool), "square"),
    (np.zeros((0, 0), bool), "n >= 1"),
    (np.zeros((4, 4)), "dtype bool, got dtype float64"),
    (np.zeros((4, 4), int), "dtype bool, got dtype int"),
    ([[True, False], [False, True]], "numpy.ndarray of bool, got list"),
])
def test_label_rejects_bad_masks(bad, match):
    with pytest.raises(ValueError, match=match):
        label_clusters(bad)


def test_other_bad_input():
    m = np.ones((4, 4), bool)
    for length in (0.0, -1.0, np.inf, "1", True):
        with pytest.raises(ValueError, match="length"):
            cluster_statistics(m, length=length)
    with pytest.raises(ValueError, match="whole node counts"):
        cluster_area_histogram([1.5], 16)
    with pytest.raises(ValueError, match=r"\[1, n_total_pixels=16\]"):
        cluster_area_histogram([17], 16)
    with pytest.raises(ValueError, match="strictly increasing"):
        cluster_area_histogram([1], 16, bins=[0.5, 0.1])
    with pytest.raises(ValueError, match="> 0"):
        cluster_area_histogram([1], 16, bins=[0.0, 1.0])
    with pytest.raises(ValueError, match="one entry per field"):
        cluster_dataset([m, m], steps=[1], length=1.0)
    with pytest.raises(ValueError, match="share one shape"):
        cluster_dataset([m, np.ones((5, 5), bool)], steps=[1, 2], length=1.0)
    with pytest.raises(ValueError, match="non-finite"):
        cluster_dataset([np.full((4, 4), np.nan)], steps=[1], length=1.0)
    with pytest.raises(ValueError, match="empty"):
        cluster_dataset([], steps=[], length=1.0)
    with pytest.raises(ValueError, match="square 2-D"):
        cluster_dataset([np.ones((4, 5))], steps=[1], length=1.0)


# --------------------------------------------------------------------------- real solution
def test_cluster_areas_sum_to_the_solver_area_fraction():
    solver = pytest.importorskip("roughcontact.solver", reason="solver not importable")
    from roughcontact import generate_surface

    h = generate_surface(64, 4, 16, 0.8, 0, rms_slope=0.1)
    res = solver.solve_contact(h, [0.001, 0.003], store_fields=True)
    ds = cluster_dataset(res.contact_pressure, res.step.values, length=1.0)
    for k in range(res.sizes["step"]):
        st = cluster_statistics(res.contact_pressure.values[k] > 0)
        assert st["areas"].sum() == pytest.approx(float(res.area_fraction[k]), rel=1e-12)
        assert st["count"] >= 1 and ds.cluster_count.values[k] == st["count"]
        np.testing.assert_array_equal(label_clusters(res.contact_pressure.values[k] > 0)[0],
                                      bfs_labels(res.contact_pressure.values[k] > 0))
    merged = res.merge(ds)
    assert "cluster_count" in merged and "area_fraction" in merged
