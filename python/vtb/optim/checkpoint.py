"""The optimiser's checkpoints: its whole state after every generation, written atomically,
read back without unpickling anything, and refused for another run."""

from __future__ import annotations

import hashlib
import json
import os
import uuid
import zipfile
from dataclasses import asdict
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import config_error, stale_file_error, writing
from .problem import Generation

_CHECKPOINT_FORMAT = "vtb.moga checkpoint 1"
_FORMAT_NAME, _FORMAT_NUMBER = _CHECKPOINT_FORMAT.rsplit(" ", 1)


def vtb_version() -> str:
    from ..config.gateway import __version__

    return __version__


def _epoch() -> int:
    from ..config.gateway import RESULTS_EPOCH

    return RESULTS_EPOCH


def written_by() -> dict:
    """What a journal, checkpoint or designs journal is stamped with: the vtb version and the
    results epoch (:data:`vtb.RESULTS_EPOCH`)."""
    return {"vtb": vtb_version(), "epoch": _epoch()}


def check_written_by(stamp: dict, field: str, path, where: str = "") -> None:
    """Refuses to resume from the file ``path`` (named by ``field``) whose ``stamp`` holds a
    results epoch other than this vtb's: an older epoch gives other results, which a resumed
    study must not mix with this vtb's; a newer one was written by a newer vtb. A change of
    the vtb version alone is no reason. A file from before the epochs (no ``epoch``) is
    refused only when another vtb version wrote it."""
    version, epoch = stamp.get("vtb"), stamp.get("epoch")
    if epoch is None:
        if version is not None and version != vtb_version():
            raise stale_file_error(field, path, f"{where}written by vtb {version}, which carried no results epoch; this vtb {vtb_version()} "
                                                "may give other results, and a resume must not mix the two: start afresh (another path, "
                                                "or move the file aside)")
        return
    if isinstance(epoch, bool) or not isinstance(epoch, int):
        raise config_error(field, str(path), f"{where}the results epoch {epoch!r} is not an integer: the file is damaged")
    if epoch > _epoch():
        raise stale_file_error(field, path, f"{where}written by a newer vtb ({version or 'unknown version'}, results epoch {epoch}); this "
                                            f"vtb {vtb_version()} has epoch {_epoch()}: upgrade vtb to resume it")
    if epoch < _epoch():
        raise stale_file_error(field, path, f"{where}the results of this vtb {vtb_version()} (results epoch {_epoch()}) differ from the file's "
                                            f"(vtb {version or 'unknown version'}, epoch {epoch}), and a resume must not mix the two: start "
                                            "afresh (another path, or move the file aside), or finish it with the older vtb")


def _identity(problem, algorithm, pop_size, n_gen, opts, rng, hv_ref, stop_hv, given, extra) -> dict:
    """What a checkpoint belongs to, as plain JSON values (compared on resume)."""
    try:
        seed_state = json.loads(json.dumps(rng.bit_generator.state))
    except TypeError:
        raise config_error("seed", type(rng.bit_generator).__name__, "a checkpoint needs a bit generator whose state is plain integers (PCG64, numpy's default)") from None
    digest = hashlib.sha256()
    for a in given[1:4]:
        digest.update(repr(a.shape).encode() + np.ascontiguousarray(a).tobytes())
    identity = dict(
        algorithm=algorithm, pop_size=pop_size, n_gen=n_gen,
        options={k: None if v is None else float(v) for k, v in opts.items()},
        lower=problem.lower.tolist(), upper=problem.upper.tolist(), log_scale=problem.log_scale.tolist(),
        n_obj=problem.n_obj, n_constr=problem.n_constr, seed=seed_state,
        hv_ref=None if hv_ref is None else np.asarray(hv_ref, dtype=float).tolist(),
        stop_hv=None if stop_hv is None else list(stop_hv), initial=digest.hexdigest() if len(given[0]) else None,
    )
    try:
        identity["problem"] = json.loads(json.dumps(extra))
    except (TypeError, ValueError):
        raise config_error("checkpoint_identity", type(extra).__name__, "must be JSON-serialisable") from None
    return identity


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


def clean_stale_temps(directory: Path, prefix: str) -> list:
    """Removes the temporary files ``<prefix><pid>.<anything>.tmp`` in ``directory`` whose
    writer (process ``pid`` on this machine) is dead — what a SIGKILL in the middle of a write
    leaves behind. Returns the paths removed."""
    removed = []
    try:
        names = os.listdir(directory)
    except OSError:
        return removed
    for name in names:
        if not (name.startswith(prefix) and name.endswith(".tmp")):
            continue
        pid = name[len(prefix):].split(".", 1)[0]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            try:
                os.unlink(os.path.join(directory, name))
                removed.append(Path(directory) / name)
            except OSError:
                pass
    return removed


def write_atomically(path: Path, write: Callable) -> None:
    """Replaces ``path`` by what ``write(binary file)`` writes, atomically: into a temporary file
    of the same directory, fsynced, renamed over ``path``, and the directory fsynced, so that a
    crash leaves either the old file or the new one, never a mixture. The temporary files of
    ``path`` a killed writer left are removed first (:func:`clean_stale_temps`)."""
    clean_stale_temps(path.parent, f".{path.name}.")
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies, unlike mkstemp's 0600
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    dir_fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)


def _save_checkpoint(path: Path, identity: dict, algo, rng, n_evals: int, history: list, message: str) -> None:
    header = dict(
        format=_CHECKPOINT_FORMAT, **written_by(), identity=identity, rng=rng.bit_generator.state, n_evals=n_evals,
        message=message, history=[asdict(h) for h in history],
    )
    with writing("checkpoint", path):
        write_atomically(path, lambda f: np.savez(f, header=np.array(json.dumps(header)), **algo.state()))


def saved_identity(path: Path):
    """The identity a checkpoint was saved with, or ``None`` if ``path`` holds no readable one."""
    try:
        with np.load(path, allow_pickle=False) as z:
            return json.loads(str(z["header"])).get("identity")
    except (OSError, EOFError, ValueError, KeyError, AttributeError, TypeError, zipfile.BadZipFile):
        return None


def _resume(path: Path, identity: dict, algo, rng, evaluate, n_gen: int) -> tuple:
    """Restores ``algo``, ``rng`` and the evaluation count from the checkpoint ``path``;
    returns its history and stop message."""
    try:
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(str(z["header"]))
            state = {k: z[k] for k in z.files if k != "header"}
    except (OSError, EOFError, ValueError, KeyError, TypeError, zipfile.BadZipFile) as e:
        raise config_error("checkpoint", str(path), f"is not a readable vtb.moga checkpoint ({type(e).__name__}: {e})") from None
    fmt = header.get("format") if isinstance(header, dict) else None
    if isinstance(fmt, str) and fmt.startswith(_FORMAT_NAME + " ") and fmt != _CHECKPOINT_FORMAT:
        number = fmt[len(_FORMAT_NAME) + 1:]
        newer = number.isdigit() and int(number) > int(_FORMAT_NUMBER)
        raise stale_file_error("checkpoint", path, (f"was written by a newer vtb ({header.get('vtb', 'unknown version')}, {fmt!r}) that this vtb "
                                                    f"{vtb_version()} cannot read: upgrade vtb, or delete it to start afresh") if newer else
                               f"is a {fmt!r} file of an older vtb; this vtb reads {_CHECKPOINT_FORMAT!r}: delete it to start afresh")
    if fmt != _CHECKPOINT_FORMAT:
        raise config_error("checkpoint", str(path), f"is not a {_CHECKPOINT_FORMAT!r} file")
    check_written_by(header, "checkpoint", path)
    saved = header.get("identity")
    if saved != identity:
        differ = sorted(k for k in identity if not isinstance(saved, dict) or saved.get(k) != identity[k])
        raise stale_file_error("checkpoint", path, f"belongs to another run (it differs in {', '.join(differ) or 'its fields'}); delete it or choose another path")
    n, p = identity["pop_size"], algo.space.problem
    shapes = dict(Z=(n, p.n_var), X=(n, p.n_var), F=(n, p.n_obj), G=(n, p.n_constr), CV=(n,), rank=(n,), crowd=(n,))
    try:
        bad = [k for k in algo._STATE if k not in state] + [k for k, s in shapes.items() if state[k].shape != s]
        history = [Generation(**g) for g in header["history"]]
        if bad or not 1 <= len(history) <= n_gen or history[-1].gen != len(history):
            raise ValueError(f"arrays {bad}, {len(history)} generations")
        algo.restore(state)
        rng.bit_generator.state = header["rng"]
        evaluate.n_evals = int(header["n_evals"])
        return history, str(header["message"])
    except (KeyError, TypeError, ValueError, AttributeError) as e:
        raise config_error("checkpoint", str(path), f"is damaged ({type(e).__name__}: {e})") from None
