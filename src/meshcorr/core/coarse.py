"""Coarse copies of a mesh: a few thousand vertices standing for all of it, and the way back.

The whole-map choice (docs/method.md, "coarse to fine") compares many
complete candidate maps; its cost grows with the vertex count, while what
it decides (which global configuration is right: left/right, front/back,
which limb is which) is visible on a copy of a few thousand vertices. A
coarse copy is made by edge collapse: libigl's ``decimate`` collapses the
shortest edge first, placing the merged vertex at the edge midpoint, and
refuses collapses that would break the manifold (the link condition), so
the copy has the fine mesh's topology. It is written by libigl because no
other library in use keeps a manifold while decimating
(``fast-simplification`` leaves duplicate faces and loose pieces).

Each coarse vertex has a *parent*, the fine vertex it was born from, and
each fine vertex a *child*, the coarse vertex nearest to it in space. A map
between two coarse copies becomes a map between the fine meshes by
:math:`T(f) = \\mathrm{parent}_2(T_c(\\mathrm{child}_1(f)))`
(:meth:`CoarseCopy.lift_map`), a start that the fine refinement then sharpens.
"""

from __future__ import annotations

import multiprocessing
import signal
import sys
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..errors import MeshError
from ..runtime.timing import peak_resident_mib
from .mesh import Mesh, as_mesh

__all__ = ["COARSE_ABOVE", "COARSE_VERTICES", "CoarseCopy", "coarse_copies", "coarse_copy", "needs_copy"]

#: Vertices of a coarse copy. The choice on copies of 2500 vertices turned more maps front to back
#: than on the full meshes (TOSCA gorilla -> woman, SHREC'07 humans) and on copies of 5000 vertices
#: it still changed the choice of 5 of 17 SHREC'07 pairs, either way (benchmarks/RESULTS-robustness.md).
COARSE_VERTICES = 5000
#: A mesh gets a coarse copy when it has more than this many times the copy's vertices: below it
#: the whole pipeline runs on the meshes, as the measured sets do (TOSCA 5k, SHREC'07 <= 16k).
COARSE_ABOVE = 4.0
#: Above this many vertices :func:`coarse_copies` decimates in child processes (one per mesh, in
#: parallel); below it libigl's ~0.5 s is less than a process start.
PROCESS_ABOVE = 200_000
#: Seconds between two looks at the child processes (a Ctrl-C is honoured within it).
_POLL = 0.1


@dataclass(frozen=True)
class CoarseCopy:
    """A coarse copy of a mesh and its links to the fine mesh.

    Attributes
    ----------
    mesh : Mesh
        The coarse mesh (``m`` vertices), named as the fine one; the fine
        mesh itself when it is not larger than the copy would be.
    parent : (m,) int
        Fine vertex each coarse vertex was born from.
    child : (n,) int
        Coarse vertex nearest each fine vertex.
    fine : Mesh
        The mesh it is a copy of.
    """

    mesh: Mesh
    parent: np.ndarray
    child: np.ndarray
    fine: Mesh

    @property
    def is_identity(self) -> bool:
        """Whether the copy is the fine mesh itself."""
        return len(self.parent) == len(self.child)

    def lift_map(self, coarse_map: np.ndarray, target: "CoarseCopy") -> np.ndarray:
        """A map between coarse copies as a map between the fine meshes.

        Parameters
        ----------
        coarse_map : (m1,) int
            ``coarse_map[c]``: target coarse vertex of source coarse vertex c.
        target : CoarseCopy
            The target's coarse copy.

        Returns
        -------
        fine_map : (n1,) int
            :math:`\\mathrm{parent}_2(T_c(\\mathrm{child}_1(f)))` for each fine source vertex f.
        """
        return target.parent[np.asarray(coarse_map)[self.child]]


def needs_copy(n_mesh: int, n_vertices: int = COARSE_VERTICES, above: float = COARSE_ABOVE) -> bool:
    """Whether a mesh of ``n_mesh`` vertices gets a coarse copy of ``n_vertices`` (0: never)."""
    return 0 < n_vertices and n_mesh > above * n_vertices


def coarse_copy(mesh: Mesh, n_vertices: int = COARSE_VERTICES, *, above: float = COARSE_ABOVE) -> CoarseCopy | None:
    """A coarse copy of ``mesh`` with about ``n_vertices`` vertices (module docstring).

    Parameters
    ----------
    mesh : Mesh
        A triangle mesh (closed or with boundary), manifold.
    n_vertices : int
        Vertices wanted; a mesh with at most ``above`` times as many keeps
        its own vertices (the copy is the identity).
    above : float
        Default :data:`COARSE_ABOVE`.

    Returns
    -------
    copy : CoarseCopy or None
        None when the mesh cannot be decimated to a valid mesh (a point
        cloud, or an edge collapse that stops early or leaves a mesh that
        :func:`meshcorr.core.validate` refuses): the caller then works on
        the fine mesh.
    """
    return coarse_copies([mesh], n_vertices, above=above)[0]


def coarse_copies(meshes: list[Mesh], n_vertices: int = COARSE_VERTICES, *, above: float = COARSE_ABOVE,
                  processes: bool | None = None, memory: dict | None = None) -> list[CoarseCopy | None]:
    """:func:`coarse_copy` of each mesh, the large ones decimated side by side in child processes.

    libigl's ``decimate`` holds the interpreter for its whole run (~25 s at
    1.28M vertices): in the calling process it could neither use the second
    core nor be stopped by Ctrl-C. Above :data:`PROCESS_ABOVE` vertices
    (``processes=None``) each mesh is decimated in a forked child process
    (POSIX; in this process elsewhere) that returns only the coarse mesh and
    its parents; the caller waits in steps of 0.1 s, so a Ctrl-C stops the
    children and raises KeyboardInterrupt within that.

    Parameters
    ----------
    meshes : list of Mesh
    n_vertices, above
        As :func:`coarse_copy`.
    processes : bool, optional
        Force child processes on (True) or off (False).
    memory : dict, optional
        Filled with ``"children_mib"``: the sum of the child processes' peak
        resident memory (an upper bound of what they added: pages shared with
        this process count in each), 0 without children.

    Returns
    -------
    copies : list of CoarseCopy or None
        One per mesh, as :func:`coarse_copy` returns it.
    """
    jobs = {}
    out: list[CoarseCopy | None] = []
    for index, mesh in enumerate(meshes):
        n = mesh.n_vertices
        if not needs_copy(n, n_vertices, above):
            identity = np.arange(n)
            out.append(CoarseCopy(mesh, identity, identity, mesh))
            continue
        out.append(None)
        if not mesh.is_cloud:
            jobs[index] = (np.asfortranarray(mesh.vertices, dtype=np.float64),
                           np.asfortranarray(mesh.faces, dtype=np.int32),
                           int(round(len(mesh.faces) * n_vertices / n)))
    if processes is None:
        processes = any(meshes[index].n_vertices > PROCESS_ABOVE for index in jobs)
    processes = processes and sys.platform != "win32" and "fork" in multiprocessing.get_all_start_methods()
    peaks: list[float] = []
    results = (_decimate_in_children(jobs, peaks) if processes
               else {index: _decimate(*job) for index, job in jobs.items()})
    if memory is not None:
        memory["children_mib"] = float(sum(peaks))
    for index, result in results.items():
        out[index] = None if result is None else _copy_of(meshes[index], *result, n_vertices)
    return out


def _decimate(vertices: np.ndarray, faces: np.ndarray, faces_wanted: int) -> tuple | None:
    """libigl's edge collapse: (coarse vertices, coarse faces, parents), or None where it fails."""
    import igl  # libigl (module docstring); imported here, as only large meshes need it

    try:  # (U, G, J, I): coarse vertices and faces, birth faces, birth vertices (a success flag first in
        # older libigl releases)
        coarse_vertices, coarse_faces, _, parent = igl.decimate(vertices, faces, faces_wanted)[-4:]
    except (RuntimeError, ValueError):
        return None
    return np.ascontiguousarray(coarse_vertices), np.ascontiguousarray(coarse_faces), np.asarray(parent)


def _child(connection, vertices: np.ndarray, faces: np.ndarray, faces_wanted: int) -> None:
    """A child process's work: :func:`_decimate`, sent back through ``connection``.

    The parent's Python signal handlers would run only once libigl returns: the child dies on SIGTERM
    at once (the default action) and leaves Ctrl-C to the parent, which stops it.
    """
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        result = _decimate(vertices, faces, faces_wanted)
        connection.send((result, peak_resident_mib() or 0.0))
    finally:
        connection.close()


def _decimate_in_children(jobs: dict, peaks: list) -> dict:
    """:func:`_decimate` of each job in its own forked process, all at once; Ctrl-C stops them.

    ``peaks`` gets each child's peak resident MiB."""
    context = multiprocessing.get_context("fork")
    running = {}
    results: dict = {}
    try:
        for index, job in jobs.items():
            receiver, sender = context.Pipe(duplex=False)
            process = context.Process(target=_child, args=(sender, *job), daemon=True,
                                      name="meshcorr-decimate")
            process.start()
            sender.close()  # the child holds its end: a child that dies closes the pipe
            running[index] = (process, receiver)
        for index, (process, receiver) in running.items():
            while not receiver.poll(_POLL):
                if not process.is_alive() and not receiver.poll():
                    break
            try:
                results[index], peak = receiver.recv()
                peaks.append(peak)
            except EOFError:  # the child died without an answer (killed, out of memory)
                results[index] = None
    finally:
        for process, receiver in running.values():
            if process.is_alive():
                process.kill()  # SIGKILL: nothing of the child's is worth keeping
            process.join()
            receiver.close()
    return results


def _copy_of(mesh: Mesh, coarse_vertices: np.ndarray, coarse_faces: np.ndarray, parent: np.ndarray,
             n_vertices: int) -> CoarseCopy | None:
    """The CoarseCopy of a decimation's result, or None where it stopped early or is not a valid mesh."""
    if len(coarse_vertices) > 1.5 * n_vertices:  # the collapses stopped early (the link condition)
        return None
    try:
        coarse = as_mesh((coarse_vertices, coarse_faces), name=mesh.name)
    except MeshError:
        return None
    _, child = cKDTree(coarse.vertices).query(mesh.vertices)
    return CoarseCopy(coarse, np.asarray(parent, dtype=np.int64), np.asarray(child, dtype=np.int64), mesh)
