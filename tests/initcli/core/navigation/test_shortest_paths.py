"""initcli.core.navigation.shortest_paths: Dijkstra on a CSR graph, compiled and as plain Python,
against hand-computed answers and scipy.sparse.csgraph (skipped where SciPy is not installed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import initcli.core.navigation.shortest_paths as shortest_paths
from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
from initcli.core.navigation.grid_planner import PlanningGrid
from initcli.core.navigation.shortest_paths import NO_PREDECESSOR, CsrGraph, csr_from_edges, dijkstra

PLAIN_PYTHON = getattr(shortest_paths._dijkstra_csr, "py_func", shortest_paths._dijkstra_csr)


def _edge_lengths(graph: CsrGraph) -> dict[tuple[int, int], float]:
    """The shortest edge u -> v of each pair."""
    out: dict[tuple[int, int], float] = {}
    for u in range(graph.n_nodes):
        for k in range(int(graph.indptr[u]), int(graph.indptr[u + 1])):
            key = (u, int(graph.indices[k]))
            out[key] = min(out.get(key, math.inf), float(graph.weights[k]))
    return out


def _assert_shortest_path_tree(graph: CsrGraph, source: int, dist: np.ndarray, pred: np.ndarray) -> None:
    """Every predecessor step is an edge that gives exactly its node's distance; only the source
    and the unreachable nodes have none."""
    lengths = _edge_lengths(graph)
    assert dist[source] == 0.0 and pred[source] == NO_PREDECESSOR
    reached = np.isfinite(dist)
    assert np.array_equal(pred == NO_PREDECESSOR, ~reached | (np.arange(graph.n_nodes) == source))
    for v in np.flatnonzero(pred >= 0):
        u = int(pred[v])
        assert dist[u] + lengths[(u, int(v))] == dist[v]


def _grid_graph(rows: int, cols: int, rng: np.random.Generator, blocked: float = 0.2) -> CsrGraph:
    """An 8-connected grid with equal step lengths (many exactly tied shortest paths), some cells out."""
    free = rng.uniform(size=(rows, cols)) > blocked
    index = np.full((rows, cols), -1)
    nodes = np.argwhere(free)
    index[free] = np.arange(len(nodes))
    src, dst, w = [], [], []
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
        r2, c2 = nodes[:, 0] + dr, nodes[:, 1] + dc
        inside = (r2 < rows) & (c2 >= 0) & (c2 < cols)
        other = np.full(len(nodes), -1)
        other[inside] = index[r2[inside], c2[inside]]
        good = other >= 0
        src.append(np.flatnonzero(good))
        dst.append(other[good])
        w.append(np.full(int(good.sum()), 0.2 * math.hypot(dr, dc)))
    return csr_from_edges(
        len(nodes), np.concatenate(src), np.concatenate(dst), np.concatenate(w), undirected=True
    )


def test_hand_computed() -> None:
    #   0 --1--> 1 --1--> 2      0 -> 2 directly costs 3, via 1 costs 2; 3 -> 0 only: 3 unreachable
    graph = csr_from_edges(4, np.array([0, 1, 0, 3]), np.array([1, 2, 2, 0]), np.array([1.0, 1.0, 3.0, 0.5]))
    assert graph.n_nodes == 4
    assert graph.indptr.tolist() == [0, 2, 3, 3, 4]
    for kernel in (dijkstra, None):
        if kernel is None:
            dist, pred = PLAIN_PYTHON(graph.indptr, graph.indices, graph.weights, 0)
        else:
            dist, pred = kernel(graph, 0)
        assert dist.tolist() == [0.0, 1.0, 2.0, math.inf]
        assert pred.tolist() == [NO_PREDECESSOR, 0, 1, NO_PREDECESSOR]
    dist, pred = dijkstra(
        csr_from_edges(4, np.array([0, 1, 0, 3]), np.array([1, 2, 2, 0]), np.ones(4), undirected=True), 2
    )
    assert dist.tolist() == [1.0, 1.0, 0.0, 2.0]
    assert pred.tolist() == [2, 2, NO_PREDECESSOR, 0]


def test_edge_cases_and_bad_input() -> None:
    lonely = csr_from_edges(3, np.array([], dtype=int), np.array([], dtype=int), np.array([]))
    dist, pred = dijkstra(lonely, 1)
    assert dist.tolist() == [math.inf, 0.0, math.inf] and pred.tolist() == [NO_PREDECESSOR] * 3
    parallel = csr_from_edges(2, np.array([0, 0]), np.array([1, 1]), np.array([2.0, 0.5]))
    assert dijkstra(parallel, 0)[0].tolist() == [0.0, 0.5]
    zero = csr_from_edges(3, np.array([0, 1]), np.array([1, 2]), np.array([0.0, 1.0]))
    assert dijkstra(zero, 0)[0].tolist() == [0.0, 0.0, 1.0]
    with pytest.raises(ValueError):
        dijkstra(lonely, 3)
    with pytest.raises(ValueError):
        csr_from_edges(2, np.array([0]), np.array([2]), np.array([1.0]))
    with pytest.raises(ValueError):
        csr_from_edges(2, np.array([0]), np.array([1]), np.array([-1.0]))
    with pytest.raises(ValueError):
        csr_from_edges(2, np.array([0]), np.array([1]), np.array([math.nan]))
    with pytest.raises(ValueError):
        csr_from_edges(2, np.array([0, 1]), np.array([1]), np.array([1.0]))


@pytest.mark.parametrize("seed", range(4))
def test_compiled_and_plain_python_agree_on_tied_grids(seed: int) -> None:
    rng = np.random.default_rng(seed)
    graph = _grid_graph(25, 40, rng)
    source = int(rng.integers(graph.n_nodes))
    dist, pred = dijkstra(graph, source)
    plain_dist, plain_pred = PLAIN_PYTHON(graph.indptr, graph.indices, graph.weights, source)
    assert np.array_equal(dist, plain_dist) and np.array_equal(pred, plain_pred)
    _assert_shortest_path_tree(graph, source, dist, pred)


def test_compiles_with_numba() -> None:
    numba = pytest.importorskip("numba")
    kernel = shortest_paths._dijkstra_csr
    if not isinstance(kernel, numba.core.registry.CPUDispatcher):
        pytest.skip("compiled() does not use numba here")
    dijkstra(csr_from_edges(2, np.array([0]), np.array([1]), np.array([1.0])), 0)
    assert kernel.signatures  # nopython mode: no object-mode fallback in numba >= 0.59


def _random_graph(rng: np.random.Generator, n: int, m: int, integer: bool) -> tuple[np.ndarray, ...]:
    src, dst = rng.integers(0, n, m), rng.integers(0, n, m)
    keep = np.unique(src * n + dst, return_index=True)[1]  # one edge per pair (scipy sums repeats)
    w = rng.integers(1, 4, m).astype(float) if integer else rng.uniform(0.01, 3.0, m)
    return src[keep], dst[keep], w[keep]


@pytest.mark.parametrize(("seed", "integer"), [(0, False), (1, False), (2, True), (3, True)])
def test_random_graphs_agree_with_scipy(seed: int, integer: bool) -> None:
    sparse = pytest.importorskip("scipy.sparse")
    csgraph = pytest.importorskip("scipy.sparse.csgraph")
    rng = np.random.default_rng(seed)
    n = 600
    src, dst, w = _random_graph(rng, n, 2400, integer)  # integer lengths: many exact ties
    for undirected in (False, True):
        graph = csr_from_edges(n, src, dst, w, undirected=undirected)
        matrix = sparse.coo_matrix((w, (src, dst)), shape=(n, n)).tocsr()
        for source in rng.integers(0, n, 5):
            ref_dist, ref_pred = csgraph.dijkstra(
                matrix, directed=not undirected, indices=int(source), return_predecessors=True
            )
            dist, pred = dijkstra(graph, int(source))
            np.testing.assert_allclose(dist, ref_dist, rtol=0, atol=1e-9)
            assert np.array_equal(dist, ref_dist)  # the same sums: equal to the float
            _assert_shortest_path_tree(graph, int(source), dist, pred)
            assert np.array_equal(pred < 0, ref_pred < 0)


def test_planning_grid_agrees_with_scipy() -> None:
    """A storey-like grid: rooms off a corridor, the planner's 8-connected graph with clearance costs."""
    sparse = pytest.importorskip("scipy.sparse")
    csgraph = pytest.importorskip("scipy.sparse.csgraph")
    res = 0.05
    world = np.full((240, 600), FREE, dtype=np.uint8)
    world[[0, -1], :] = OCCUPIED
    world[:, [0, -1]] = OCCUPIED
    world[100:104, :] = OCCUPIED  # the corridor's wall, with doorways
    for col in range(40, 600, 80):
        world[100:104, col : col + 18] = FREE
        world[:100, col + 40 : col + 42] = OCCUPIED  # walls between the rooms
    grid = OccupancyGrid(np.flipud(world).copy(), res, (0.0, 0.0, 0.0))
    for prefer in (0.0, 0.6):
        planner = PlanningGrid.of(grid, clearance=0.3, cell=0.2, prefer=prefer)
        g = planner.graph
        rows = np.repeat(np.arange(g.n_nodes), np.diff(g.indptr))
        matrix = sparse.csr_matrix((g.weights, (rows, g.indices)), shape=(g.n_nodes, g.n_nodes))
        for x, y in [(2.0, 2.0), (15.0, 7.0), (29.0, 11.0)]:
            dist, pred, start = planner.distances_from(x, y)
            ref_dist, _ = csgraph.dijkstra(matrix, indices=start, return_predecessors=True)
            assert start >= 0 and np.isfinite(dist).sum() > 0.9 * g.n_nodes
            np.testing.assert_allclose(dist, ref_dist, rtol=0, atol=1e-9)
            _assert_shortest_path_tree(g, start, dist, pred)
