"""The outputs of egogen's tools: the checks a tool runs on its output paths before any work
(an existing path is refused unless the tool was given --replace; an output inside the tool's
input is refused always), and the writing of each output through `<path>.partial`, flushed to
disk and renamed over the path, so an interrupted tool leaves no half-written output.

    import outputs
    outputs.check_new(args.out, "--out", args.replace)
    outputs.check_outside(args.out, "--out", args.take, "the take")
    ...
    outputs.write_json(args.out, doc, args.replace)
    with outputs.writing(args.png, args.replace) as tmp:   # for savefig, PIL, numpy, tools
        fig.savefig(tmp, format="png")

Standard library only. Scripts import it from tools/ (`python3 tools/x.py` puts tools/ on
sys.path; one run another way, e.g. under `blender --python`, inserts its own folder first).
"""
import contextlib
import json
import os
from pathlib import Path

PARTIAL = ".partial"


class OutputError(SystemExit):
    """An output refused: a SystemExit, so a script that does not catch it ends with the
    message on stderr and exit status 1 (as `sys.exit(message)` does)."""

    def __init__(self, message):
        super().__init__(message)
        self.message = message

    def __str__(self):
        return self.message


def partial_path(path) -> Path:
    """Where `path` is written before it is renamed into place: `<path>.partial`."""
    p = Path(path)
    return p.with_name(p.name + PARTIAL)


def format_of(path, default="png") -> str:
    """The format a writer that goes by the file name would choose for `path` (its extension,
    lower case): for writing the same format to `<path>.partial`."""
    return Path(path).suffix[1:].lower() or default


def check_new(path, flag, replace=False, folder=False, parents=False) -> Path:
    """Refuses `path` (given as `flag`, e.g. "--out") when it exists and `replace` is false
    (None: the tool has no --replace for it); with `replace`, when it is a folder and a file is
    to be written (`folder` false) or the other way round; and, unless `parents` (the tool
    creates them), when its folder does not exist. Returns it as a Path."""
    p = Path(path)
    label = f"{flag} {path}" if flag else str(path)
    if p.exists() or p.is_symlink():
        if replace is None:
            raise OutputError(f"{label}: exists; choose a new path")
        if not replace:
            raise OutputError(f"{label}: exists; choose a new path or pass --replace")
        if p.is_dir() != folder:
            what = "a folder" if p.is_dir() else "a file"
            raise OutputError(f"{label}: exists and is {what}; choose a new path")
    parent = p.parent if str(p.parent) else Path(".")
    if not parents and not parent.is_dir():
        raise OutputError(f"{label}: no such folder {parent}; create it first")
    return p


def check_new_all(paths, flag, replace=False, parents=False) -> list:
    """check_new for each of the files one flag writes (e.g. the files of an --out folder)."""
    return [check_new(p, flag, replace, parents=parents) for p in paths]


def check_outside(path, flag, input_path, input_name="the input"):
    """Refuses an output `path` inside the input folder `input_path`, or the same file as the
    input file `input_path`."""
    out = Path(os.path.realpath(path))
    inp = Path(os.path.realpath(input_path))
    label = f"{flag} {path}" if flag else str(path)
    if out == inp:
        raise OutputError(f"{label}: is {input_name} {input_path}; choose another path")
    if inp in out.parents:
        raise OutputError(f"{label}: inside {input_name} {input_path}; choose a path outside it")


def _fsync(path):
    if Path(path).is_file():
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _fsync_folder(folder):
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _remove(path):
    with contextlib.suppress(FileNotFoundError):
        os.remove(path)


@contextlib.contextmanager
def writing(path, replace=False):
    """Yields `<path>.partial` for the caller (or a program it runs) to write; when the block
    ends without an error, flushes it to disk and renames it to `path`; on an error (or an
    interrupt) removes it. Without `replace` a `path` that appeared meanwhile is not
    overwritten (an OutputError, the partial removed)."""
    p = Path(path)
    tmp = partial_path(p)
    _remove(tmp)  # a partial left by an earlier, killed run
    try:
        yield tmp
        if not tmp.is_file():
            raise OutputError(f"{path}: nothing was written to {tmp}")
        _fsync(tmp)
        if replace:
            os.replace(tmp, p)
        else:
            try:
                os.link(tmp, p)  # fails if p exists: nothing is overwritten
            except FileExistsError:
                raise OutputError(f"{path}: exists; choose a new path or pass --replace") from None
            except OSError:  # a file system without hard links
                if p.exists():
                    raise OutputError(f"{path}: exists; choose a new path or pass --replace") from None
                os.replace(tmp, p)
        _fsync_folder(p.parent if str(p.parent) else ".")
    finally:
        _remove(tmp)


def write_bytes(path, data, replace=False):
    with writing(path, replace) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)


def write_text(path, text, replace=False, encoding="utf-8"):
    """Writes `text` as is (newline="" : no newline translation)."""
    with writing(path, replace) as tmp:
        with open(tmp, "w", encoding=encoding, newline="") as f:
            f.write(text)


def write_json(path, doc, replace=False, **dumps):
    """json.dumps(doc, **dumps) (indent 2 when none is given) and a final newline."""
    dumps.setdefault("indent", 2)
    write_text(path, json.dumps(doc, **dumps) + "\n", replace)
