"""The folder of each job under the output root: made on demand, never a way out of the root.

A symbolic link planted where a job's folder goes (``results/cut4 -> /home/me``) would make the job
write its log and results through it; so would a link among the root's own subfolders. Every job's
folder must be a real directory whose real path lies inside the root's real path.

:func:`scenario_to_run` says which scenario file a job runs: the original, or on a host without it the
copy the store keeps, written into the job's folder.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:       # (the fork server makes job folders with this module: it loads no more than it needs)
    from store.jobs import Batch, Job
    from store.queue import QueueStore


def prepare_job_folder(root: Path, folder: Path, real_root: str) -> bool:
    """Create a job's folder under the output root, refusing one that leads elsewhere (see the module doc);
    returns whether it made the folder (False: it was there).

    ``real_root``: the root's real path, resolved once per batch (:class:`JobFolders`). A folder right
    inside the root needs no path resolution: being a real directory (not a link) in the root, its
    real path is inside the root's.
    """
    made = True
    if folder.parent == root and folder.name not in ("", ".", ".."):
        try:
            os.mkdir(folder)
        except FileExistsError:
            made = False
        except FileNotFoundError:         # the root went away meanwhile: make it again
            root.mkdir(parents=True, exist_ok=True)
            folder.mkdir(exist_ok=True)
        mode = os.lstat(folder).st_mode
        if stat.S_ISLNK(mode):
            raise OSError(f"the job folder {folder} is a symbolic link; refusing to write through it")
        if not stat.S_ISDIR(mode):
            raise FileExistsError(f"the job folder {folder} exists and is not a folder")
        return made
    if folder.is_symlink():
        raise OSError(f"the job folder {folder} is a symbolic link; refusing to write through it")
    made = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    real = folder.resolve()
    if not real.is_relative_to(real_root):
        raise OSError(f"the job folder {folder} leads out of {root} (to {real}); refusing to write there")
    return made


class JobFolders:
    """Prepares job folders, resolving each output root once (a worker makes thousands of folders)."""

    def __init__(self) -> None:
        self._real_roots: dict[str, str] = {}    # output root -> its real path

    def prepare(self, root: Path, folder: Path) -> bool:
        """:func:`prepare_job_folder`, the root made and its real path resolved on its first job."""
        return prepare_job_folder(root, folder, self.real_root(root))

    def real_root(self, root: Path) -> str:
        """The root's real path, the root made on its first job (for a job folder made elsewhere: the
        built-in runner's fork server makes it as the job starts, with :func:`prepare_job_folder`)."""
        key = str(root)
        real = self._real_roots.get(key)
        if real is None:
            root.mkdir(parents=True, exist_ok=True)
            real = self._real_roots[key] = os.path.realpath(root)
        return real


def scenario_to_run(store: QueueStore, job: Job, batch: Batch, output_dir: Path) -> str:
    """The scenario path a job runs: the original file, or (on a host without it, or with another
    version of it) the copy kept in the store, written into the job's folder."""
    import hashlib  # (here: the fork server, which uses this module, loads no more than a job would)

    path = job.scenario_path
    if batch.mode == "local":
        return path
    try:
        if hashlib.sha256(Path(path).read_bytes()).hexdigest() == job.scenario_sha:
            return path
    except OSError:
        pass
    text = store.scenario_text(job.id)
    if text is None:
        return path
    output_dir.mkdir(parents=True, exist_ok=True)
    copy = output_dir / Path(path).name
    copy.write_text(text, encoding="utf-8")
    return str(copy)
