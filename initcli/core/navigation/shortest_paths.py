"""Single-source shortest paths on a weighted graph in CSR form (Dijkstra with a binary heap).

A graph is :class:`CsrGraph`: the edges leaving node ``u`` are ``indices[indptr[u]:indptr[u + 1]]``
with the (non-negative) lengths ``weights[indptr[u]:indptr[u + 1]]`` -- the layout of a CSR
sparse matrix whose entry ``(u, v)`` is the length of the edge u -> v. :func:`dijkstra` answers
what ``scipy.sparse.csgraph.dijkstra(graph, indices=source, return_predecessors=True)`` answers:
the path lengths from ``source`` (``inf`` where unreachable) and each node's predecessor on a
shortest path (``NO_PREDECESSOR`` = -9999 for the source and unreachable nodes). The lengths are
the same sums in the same order, so equal to the float; where two paths are exactly equally
short the predecessor may be another one of them.

The loop (E. W. Dijkstra, 1959; a binary heap of ``(distance, node)`` with lazy deletion, as
``heapq``) is compiled by :func:`initcli.core.geometry.jit.compiled` where numba is installed and
runs as plain Python where it is not.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.jit import compiled

__all__ = ["NO_PREDECESSOR", "CsrGraph", "csr_from_edges", "dijkstra"]

NO_PREDECESSOR = -9999  # the source and the unreachable nodes


@dataclass(frozen=True)
class CsrGraph:
    """A directed graph of ``n_nodes`` nodes: the edges leaving ``u`` are ``indices[indptr[u]:
    indptr[u + 1]]`` with lengths ``weights[...]`` (int64, int64, float64)."""

    indptr: np.ndarray
    indices: np.ndarray
    weights: np.ndarray

    @property
    def n_nodes(self) -> int:
        return int(self.indptr.shape[0]) - 1


def csr_from_edges(
    n_nodes: int, src: np.ndarray, dst: np.ndarray, weights: np.ndarray, *, undirected: bool = False
) -> CsrGraph:
    """The graph of the edges ``src[k] -> dst[k]`` of length ``weights[k]`` (non-negative, finite);
    ``undirected``: each edge also runs back. Edges stay in their given order within a node;
    repeated edges are kept as parallel edges (a path takes the shortest)."""
    src = np.asarray(src, dtype=np.int64).reshape(-1)
    dst = np.asarray(dst, dtype=np.int64).reshape(-1)
    weights = np.asarray(weights, dtype=np.float64).reshape(-1)
    if not src.shape == dst.shape == weights.shape:
        raise ValueError("src, dst and weights must have the same length")
    if src.size and (min(src.min(), dst.min()) < 0 or max(src.max(), dst.max()) >= n_nodes):
        raise ValueError(f"edge end outside 0..{n_nodes - 1}")
    if not np.all(np.isfinite(weights) & (weights >= 0.0)):
        raise ValueError("edge lengths must be finite and non-negative")
    if undirected:
        src, dst = np.concatenate([src, dst]), np.concatenate([dst, src])
        weights = np.concatenate([weights, weights])
    order = np.argsort(src, kind="stable")
    indptr = np.zeros(n_nodes + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n_nodes), out=indptr[1:])
    return CsrGraph(indptr, dst[order], weights[order])


@compiled
def _dijkstra_csr(
    indptr: np.ndarray, indices: np.ndarray, weights: np.ndarray, source: int
) -> tuple[np.ndarray, np.ndarray]:
    """Dijkstra from ``source``: (dist, pred). A node's distance is final when it leaves the heap;
    an edge relaxes a node only if it makes the path strictly shorter."""
    n = indptr.shape[0] - 1
    dist = np.full(n, np.inf)
    pred = np.full(n, NO_PREDECESSOR, dtype=np.int64)
    done = np.zeros(n, dtype=np.bool_)
    dist[source] = 0.0
    heap = [(0.0, source)]
    while len(heap) > 0:
        d, u = heapq.heappop(heap)
        if done[u]:
            continue  # a stale entry: u was reached more cheaply since
        done[u] = True
        for k in range(indptr[u], indptr[u + 1]):
            v = indices[k]
            nd = d + weights[k]
            if nd < dist[v]:
                dist[v] = nd
                pred[v] = u
                heapq.heappush(heap, (nd, v))
    return dist, pred


def dijkstra(graph: CsrGraph, source: int) -> tuple[np.ndarray, np.ndarray]:
    """Shortest path lengths from ``source`` to every node (``inf``: unreachable) and the
    predecessors (``NO_PREDECESSOR`` for the source and the unreachable nodes)."""
    if not 0 <= source < graph.n_nodes:
        raise ValueError(f"source {source} outside 0..{graph.n_nodes - 1}")
    dist, pred = _dijkstra_csr(graph.indptr, graph.indices, graph.weights, int(source))
    return dist, pred
