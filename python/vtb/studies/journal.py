"""Study journals: CSV files a study appends each finished case to, so that it resumes.

A journal's line 1 is its stamp, ``# vtb <kind> journal {"config": {...}, "format": 1, "vtb":
"<version>"}`` (what study wrote it — ``sweep``, ``study``, ``robust sweep`` —, the studied
configuration as JSON and the vtb version that wrote it; a journal of another version is
refused rather than mixed), line 2 the CSV header — the study's variables (the keys of a
row), its indices and ``error`` —, then one row per finished run. Rows are keyed by their
variables' values (all ``nan``: the study's reference case), not by a case number, so that a
changed grid reuses every row it shares. Used by :func:`vtb.study` and :func:`vtb.sweep`.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import io
import json
import math
import os
import re
import socket
from pathlib import Path
from typing import Optional

from ..config.fields import Config
from ..errors import ConfigError, config_error, stale_file_error, writing
from ..optim.checkpoint import check_written_by, vtb_version, write_atomically, written_by

FORMAT = 1
_STAMP = "# vtb sweep journal "
#: The stamp's opening for a journal of ``kind`` (``"sweep"``: :func:`vtb.sweep`'s; ``"study"``:
#: any other :func:`vtb.study`'s; the robust study's ``"robust sweep"``).
_OPENING = re.compile(r"# vtb ([a-z ]+) journal ")


def stamp_opening(kind: str) -> str:
    return f"# vtb {kind} journal "


@dataclasses.dataclass(frozen=True)
class Layout:
    """The columns of a journal: ``keys`` (the variables' labels) and ``values`` (indices)."""

    keys: tuple
    values: tuple

    @property
    def columns(self) -> tuple:
        return tuple(self.keys) + tuple(self.values) + ("error",)

    def key(self, row: dict):
        """A row's key: its variables' values, ``None`` for the reference case (all NaN)."""
        v = tuple(float(row[k]) for k in self.keys)
        return None if all(math.isnan(x) for x in v) else v


def config_stamp(config: Config) -> str:
    """The configuration as canonical JSON: what a journal is stamped with and what a warm start
    and a checkpoint of :func:`vtb.optimize` are checked against."""
    return json.dumps(config.to_dict(), sort_keys=True)


def same_config(stamp, config: Config) -> bool:
    """Whether a stored ``stamp`` (a :func:`config_stamp`, as text or parsed) is of ``config``.
    The stamp is read back through today's schema, so a field added since it was written takes
    its default and does not make the file stale, while a changed default does (the stamp holds
    the old value); a stamp that no longer parses is another configuration."""
    try:
        stored = Config.from_dict(json.loads(stamp) if isinstance(stamp, str) else stamp)
    except (ConfigError, TypeError, ValueError):
        return False
    return config_stamp(stored) == config_stamp(config)


def csv_text(rows: list, columns: tuple, header: bool = False) -> str:
    """Rows as CSV: numbers by ``repr`` (exact round trip), ``case`` and ``error`` as they are."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n", extrasaction="ignore")
    if header:
        w.writeheader()
    for r in rows:
        w.writerow({k: (r[k] if k in ("case", "error") else repr(float(r[k]))) for k in columns})
    return buf.getvalue()


def append(journal: Path, rows: list, layout: Layout) -> None:
    """Appends rows and syncs them to the disk."""
    with open(journal, "a", newline="") as f:
        f.write(csv_text(rows, layout.columns))
        f.flush()
        os.fsync(f.fileno())


def _drop_partial_line(path: Path) -> None:
    """Cuts a last line left without its newline by a kill, so that appends stay rows."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with open(path, "r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)


def parse(path: Path, field: str, layout: Optional[Layout] = None):
    """The stamp's configuration (``None`` for an empty file), the layout (``layout``, or read
    from the header, its first ``keys`` columns (the stamp's count; 3, b_t k_t c_t, for a
    journal of :func:`vtb.sweep`) the variables) and the rows by key.

    Of several rows with one key the last successful one wins, or the last one when all failed.
    A last line without its newline (a write cut short) is ignored; anything else malformed
    raises a :class:`ConfigError` naming ``field`` and the line number.
    """
    data = path.read_bytes()
    try:
        lines = data[: data.rfind(b"\n") + 1].decode("utf-8").split("\n")[:-1]
    except UnicodeDecodeError as e:
        raise config_error(field, str(path), f"is not a vtb study journal (not UTF-8 text: {e})") from None
    if not lines:
        return None, layout, {}

    def bad(line: int, reason: str) -> ConfigError:
        return config_error(field, str(path), f"line {line}: {reason}")

    opening = _OPENING.match(lines[0])
    if opening is None:
        raise bad(1, f"not a vtb study journal (its first line must be the stamp {_STAMP.strip()!r} + JSON); choose another path")
    try:
        stamp = json.loads(lines[0][opening.end():])
        fmt = stamp["format"]
    except (ValueError, KeyError, TypeError) as e:
        raise bad(1, f"the journal's stamp does not parse ({type(e).__name__}: {e})") from None
    if isinstance(fmt, int) and not isinstance(fmt, bool) and fmt > FORMAT:
        raise bad(1, f"written by a newer vtb ({stamp.get('vtb', 'unknown version')}; journal format {fmt}), which this vtb "
                     f"{vtb_version()} (format {FORMAT}) cannot read: upgrade vtb")
    if fmt != FORMAT:
        raise bad(1, f"journal format {fmt!r}; this vtb reads format {FORMAT}")
    try:
        config = Config.from_dict(stamp["config"])
        keys = stamp.get("keys")
    except (ValueError, KeyError, TypeError) as e:  # ConfigError is a ValueError
        raise bad(1, f"the journal's stamp does not parse ({type(e).__name__}: {e})") from None
    check_written_by(stamp, field, path, "line 1: ")
    header = next(csv.reader(lines[1:2]), None)
    if layout is None:
        n = keys if isinstance(keys, int) else 3  # journals of vtb.sweep carry no key count: b_t, k_t, c_t
        if not header or header[-1] != "error" or len(header) < n + 1:
            raise bad(2, f"the header must list the variables, the indices and error, not {header}")
        layout = Layout(tuple(header[:n]), tuple(header[n:-1]))
    if header != list(layout.columns):
        raise bad(2, f"the header must be {','.join(layout.columns)}")
    rows = {}
    for number, fields in enumerate(csv.reader(lines[2:]), start=3):
        if len(fields) != len(layout.columns):
            raise bad(number, f"{len(fields)} fields, expected {len(layout.columns)}")
        row = {"error": fields[-1]}
        for name, text in zip(layout.columns[:-1], fields):
            try:
                row[name] = float(text)
            except ValueError:
                raise bad(number, f"{name} = {text!r} is not a number") from None
        params = [row[k] for k in layout.keys]
        if not (all(math.isnan(v) for v in params) or all(math.isfinite(v) for v in params)):
            raise bad(number, f"({', '.join(layout.keys)}) = {params} must be numbers, or all nan for the reference case")
        key = layout.key(row)
        if not row["error"] or key not in rows or rows[key]["error"]:
            rows[key] = row
    return config, layout, rows


@contextlib.contextmanager
def lock(journal: Path, field: str = "out", holder_kind: str = "another sweep or study"):
    """Holds ``<journal>.lock`` for a whole study. The lock is an exclusive ``fcntl.flock`` on
    that file, which the kernel releases when its process dies: the file a killed study leaves
    behind is then free again, so stale locks need no clean-up. The holder writes its pid and
    host into the file for the message of a study refused meanwhile. ``field`` names the
    argument of a refusal, ``holder_kind`` what holds the lock."""
    import fcntl  # POSIX only

    path = journal.with_name(journal.name + ".lock")
    while True:
        with writing(field, path):
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 200, 0).decode(errors="replace").strip()
            os.close(fd)
            raise config_error(field, str(journal), f"is in use by {holder_kind} ({holder or 'pid not yet written'}; lock file {path})") from None
        # the holder may have removed the file between our open and our lock: lock the new one
        try:
            if os.stat(path).st_ino == os.fstat(fd).st_ino:
                break
        except FileNotFoundError:
            pass
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode())
        yield
    finally:
        path.unlink(missing_ok=True)  # still locked: nobody can take the unlinked file unnoticed
        os.close(fd)


def open_rows(journal: Path, config: Config, layout: Layout, kind: Optional[str] = None) -> dict:
    """The rows of the journal of ``config`` by key, creating the journal if absent or empty
    (stamped ``# vtb <kind> journal``: ``kind`` default "sweep" for the dampers' b_t, k_t, c_t,
    else "study", and the vtb version); refuses one of another configuration or other
    columns, or written by another vtb version. Call it with the lock held."""
    if journal.exists():
        _drop_partial_line(journal)
        stamped, _, rows = parse(journal, "out", layout)
    else:
        stamped, rows = None, {}
    stamp = config_stamp(config)
    if stamped is None:
        head = {"format": FORMAT, "config": json.loads(stamp), **written_by()}
        sweep = layout.keys == ("b_t", "k_t", "c_t")
        if not sweep:
            head["keys"] = len(layout.keys)
        first = stamp_opening(kind or ("sweep" if sweep else "study")) + json.dumps(head, sort_keys=True) + "\n"
        write_atomically(journal, lambda f: f.write((first + csv_text([], layout.columns, header=True)).encode()))
        return {}
    if config_stamp(stamped) != stamp:
        raise stale_file_error("out", journal, "line 1: holds a study of another configuration; choose another path")
    return rows


def reuse(known: dict, cases: list, layout: Layout) -> tuple:
    """The successful journal rows of ``cases`` (dicts with ``case`` and the keys; renumbered)
    and the cases still to run."""
    rows, todo = [], []
    for case in cases:
        row = known.get(layout.key(case))
        if row is not None and not row["error"]:
            rows.append(dict(row, case=case["case"]))
        else:
            todo.append(case)
    return rows, todo
