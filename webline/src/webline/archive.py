"""Zip archives from other users (SSP archives and the FMUs inside them), read as untrusted input.

`check_archive` refuses an archive before anything is written: entry paths that are absolute or climb
out with `..`, symbolic links, duplicate names, and sizes over `Limits` (entry count, each entry, total).
`extract` then writes the entries only below a new or empty target folder, creating each file with
O_EXCL|O_NOFOLLOW and counting the bytes it really writes (a zip bomb's declared size is not trusted).
Every error names the archive and the entry.
"""

from __future__ import annotations

import os
import stat
import zipfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

MiB = 1 << 20


@dataclass(frozen=True)
class Limits:
    entries: int = 4096
    entry_bytes: int = 256 * MiB  # an FMU with binaries for several platforms stays far below
    total_bytes: int = 1024 * MiB


DEFAULT_LIMITS = Limits()
CHUNK = 1 * MiB


class ArchiveError(ValueError):
    """An archive refused: the message names the archive and the entry."""


def _safe_parts(archive: Path, name: str) -> tuple[str, ...]:
    """The path components of an entry name that stays inside the target folder."""
    if not name or "\x00" in name:
        raise ArchiveError(f"{archive}: entry {name!r}: an empty name or a NUL character")
    if "\\" in name:
        raise ArchiveError(f"{archive}: entry {name!r}: a backslash in a path (zip paths use '/')")
    p = PurePosixPath(name)
    if p.is_absolute() or (len(name) > 1 and name[1] == ":"):
        raise ArchiveError(f"{archive}: entry {name!r}: an absolute path (entries must stay inside the target folder)")
    parts = tuple(x for x in p.parts if x not in ("", "."))
    if ".." in parts:
        raise ArchiveError(f"{archive}: entry {name!r}: a '..' component (entries must stay inside the target folder)")
    if not parts:
        raise ArchiveError(f"{archive}: entry {name!r}: names no file")
    return parts


def check_archive(archive: Path, limits: Limits = DEFAULT_LIMITS) -> list[zipfile.ZipInfo]:
    """The entries of a zip archive, refused as a whole (ArchiveError) if any is unsafe or too large."""
    archive = Path(archive)
    try:
        zf = zipfile.ZipFile(archive)
    except (zipfile.BadZipFile, OSError) as e:
        raise ArchiveError(f"{archive}: not a readable zip archive ({e})") from None
    with zf:
        infos = zf.infolist()
    if len(infos) > limits.entries:
        raise ArchiveError(f"{archive}: {len(infos)} entries, more than the {limits.entries} allowed")
    seen, total = set(), 0
    for info in infos:
        parts = _safe_parts(archive, info.filename)
        mode = info.external_attr >> 16
        if stat.S_ISLNK(mode):
            raise ArchiveError(f"{archive}: entry {info.filename!r}: a symbolic link (links are not extracted)")
        if stat.S_IFMT(mode) not in (0, stat.S_IFREG, stat.S_IFDIR):  # 0: no file type recorded
            raise ArchiveError(f"{archive}: entry {info.filename!r}: not a regular file or folder (mode {mode:o})")
        key = "/".join(parts)
        if key in seen:
            raise ArchiveError(f"{archive}: entry {info.filename!r}: a second entry of the same name")
        seen.add(key)
        if info.file_size > limits.entry_bytes:
            raise ArchiveError(f"{archive}: entry {info.filename!r}: {info.file_size} bytes, more than the "
                               f"{limits.entry_bytes} allowed for one entry")
        total += info.file_size
        if total > limits.total_bytes:
            raise ArchiveError(f"{archive}: entry {info.filename!r}: the entries so far hold {total} bytes, "
                               f"more than the {limits.total_bytes} allowed in all")
    return infos


def extract(archive: Path, target: Path, limits: Limits = DEFAULT_LIMITS) -> Path:
    """Extracts a checked archive below `target` (created; it must be new or empty) and returns its
    resolved path. Nothing is written outside it; no link is created or followed."""
    archive = Path(archive)
    infos = check_archive(archive, limits)
    target = Path(target)
    target.mkdir(parents=True, exist_ok=True)
    if target.is_symlink() or any(target.iterdir()):
        raise ArchiveError(f"{archive}: the target folder {target} is not empty (or is a link): extract into a new folder")
    root = target.resolve()
    total = 0
    with zipfile.ZipFile(archive) as zf:
        for info in infos:
            parts = _safe_parts(archive, info.filename)
            folder = root
            for part in parts[:-1] if not info.is_dir() else parts:
                folder = folder / part
                if folder.is_symlink():
                    raise ArchiveError(f"{archive}: entry {info.filename!r}: its folder {folder} is a link")
                folder.mkdir(exist_ok=True)
            if info.is_dir():
                continue
            path = folder / parts[-1]
            flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
            try:
                fd = os.open(path, flags, 0o644)
            except FileExistsError:
                raise ArchiveError(f"{archive}: entry {info.filename!r}: {path} exists already") from None
            written = 0
            try:
                with os.fdopen(fd, "wb") as out, zf.open(info) as src:
                    while chunk := src.read(CHUNK):
                        written += len(chunk)
                        total += len(chunk)
                        if written > min(info.file_size, limits.entry_bytes) or total > limits.total_bytes:
                            raise ArchiveError(f"{archive}: entry {info.filename!r}: holds more bytes than it "
                                               f"declares ({info.file_size}) or than allowed")
                        out.write(chunk)
            except ArchiveError:
                path.unlink(missing_ok=True)
                raise
            except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, EOFError, ValueError) as e:
                path.unlink(missing_ok=True)
                raise ArchiveError(f"{archive}: entry {info.filename!r}: unreadable ({e})") from None
    return root


def read_bounded(path: Path, limit: int = 16 * MiB) -> bytes:
    """A user's file (a scene, a profile), read whole only if it is a regular file within `limit` bytes."""
    path = Path(path)
    st = os.stat(path)
    if not stat.S_ISREG(st.st_mode):
        raise ArchiveError(f"{path}: not a regular file")
    if st.st_size > limit:
        raise ArchiveError(f"{path}: {st.st_size} bytes, more than the {limit} allowed")
    with open(path, "rb") as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise ArchiveError(f"{path}: more than the {limit} bytes allowed")
    return data
