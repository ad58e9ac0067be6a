"""What a write may replace: only a regular file (or nothing).

Every writer -- the mesh formats, STEP through OpenCascade, PNG pictures -- goes through
``splinekit._atomic.atomic_write``, which renames a temporary file onto the target. A rename
replaces whatever the target is, so without checks ``export_stl("/dev/null")`` run as root turns
the device into a plain file, and a FIFO, a socket or a symbolic link is replaced likewise.
These tests check, for every writer, that such targets are refused (and left as they were), that
a symbolic link is kept while the file it names is replaced, that a replaced file keeps its
permissions, and that errors never name the temporary file.
"""

from __future__ import annotations

import errno
import os
import socket
import stat
import tempfile

import numpy as np
import pytest

import exporters
import splinekit as sk
from splinekit import _atomic
from splinekit.errors import ExportError, ParameterError, SplineKitError
from splinekit.mesh import primitives

IS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0


def _surface():
    x, y = np.meshgrid(np.linspace(0, 1, 4), np.linspace(0, 1, 4), indexing="ij")
    return sk.BSplineSurface.uniform(3, 3, np.stack([x, y, 0.2 * np.sin(3 * x) * y], axis=-1))


def _write_stl(path):
    return exporters.export_stl(path, primitives.box())


def _write_stl_ascii(path):
    return exporters.export_stl(path, primitives.box(), binary=False)


def _write_obj(path):
    return exporters.export_obj(path, primitives.box())


def _write_ply(path):
    return exporters.export_ply(path, primitives.box())


def _write_3mf(path):
    return exporters.export_3mf(path, primitives.box())


def _write_glb(path):
    return exporters.export_glb(path, primitives.box())


def _write_step(path):
    return exporters.export_step(path, _surface())


def _write_png(path):
    from splinekit.plot import render_mesh

    return render_mesh(primitives.box(), path, size=(64, 64), color="normal")


def _write_png_surface(path):
    from splinekit.plot import render_surface

    return render_surface(_surface(), path, resolution=8)


def _read_back(path, suffix):
    """Independent evidence that ``path`` holds a complete file of its format."""
    data = open(path, "rb").read()
    if suffix == ".png":
        assert data.startswith(b"\x89PNG\r\n\x1a\n") and data.rstrip().endswith(b"IEND\xaeB`\x82")
    elif suffix == ".step":
        assert exporters.import_step(path)
    else:
        mesh = exporters.import_mesh(path)
        assert mesh.n_faces >= 6 and mesh.is_closed


MESH_WRITERS = {".stl": _write_stl, ".obj": _write_obj, ".ply": _write_ply, ".3mf": _write_3mf, ".glb": _write_glb}
WRITERS = [(".stl", _write_stl), (".stl", _write_stl_ascii), (".obj", _write_obj), (".ply", _write_ply),
           (".3mf", _write_3mf), (".glb", _write_glb), (".step", _write_step), (".png", _write_png),
           (".png", _write_png_surface)]
WRITER_IDS = ["stl", "stl-ascii", "obj", "ply", "3mf", "glb", "step", "png-mesh", "png-surface"]


def _temporaries(*folders):
    return [name for folder in folders for name in os.listdir(folder) if name.startswith(_atomic.TEMP_PREFIX)]


# -- special files are refused and left as they are ------------------------------------------

@pytest.mark.parametrize("suffix, write", WRITERS, ids=WRITER_IDS)
def test_a_fifo_is_refused_and_kept(tmp_path, suffix, write):
    target = tmp_path / f"pipe{suffix}"
    os.mkfifo(target)
    with pytest.raises(ExportError, match="FIFO") as info:
        write(target)
    assert str(target) in str(info.value)
    assert stat.S_ISFIFO(os.lstat(target).st_mode)  # still a FIFO, not a plain file
    assert _temporaries(tmp_path) == []


@pytest.mark.parametrize("suffix, write", WRITERS, ids=WRITER_IDS)
def test_a_folder_is_refused(tmp_path, suffix, write):
    target = tmp_path / f"folder{suffix}"
    target.mkdir()
    (target / "inside").write_text("kept")
    with pytest.raises(ExportError, match="folder"):
        write(target)
    assert (target / "inside").read_text() == "kept"
    assert sorted(os.listdir(tmp_path)) == [target.name]


def test_a_socket_is_refused_and_kept():
    folder = tempfile.mkdtemp(prefix="sk-", dir="/tmp" if os.path.isdir("/tmp") else None)  # AF_UNIX paths are short
    path = os.path.join(folder, "s.stl")
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        server.bind(path)
        for write in MESH_WRITERS.values():
            with pytest.raises(ExportError, match="socket"):
                write(path)
        with pytest.raises(ExportError, match="socket"):
            _write_png(path)
        assert stat.S_ISSOCK(os.lstat(path).st_mode)
        assert _temporaries(folder) == []
    finally:
        server.close()
        os.unlink(path)
        os.rmdir(folder)


def test_a_character_device_is_refused_and_kept(tmp_path):
    """A private copy of /dev/null's device node (major 1, minor 3) made with mknod (root only),
    so that a regression cannot damage the machine's /dev/null."""
    target = tmp_path / "null.stl"
    try:
        os.mknod(target, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except (PermissionError, AttributeError, OSError) as exc:
        pytest.skip(f"cannot make a device node here: {exc}")
    before = os.lstat(target)
    for suffix, write in WRITERS:
        with pytest.raises(ExportError, match="character device"):
            write(target)
    after = os.lstat(target)
    assert stat.S_ISCHR(after.st_mode) and after.st_rdev == before.st_rdev and after.st_ino == before.st_ino
    assert _temporaries(tmp_path) == []


@pytest.mark.skipif(not os.path.exists("/dev/null") or not stat.S_ISCHR(os.stat("/dev/null").st_mode),
                    reason="no /dev/null character device")
def test_dev_null_is_refused():
    # the check first: should it ever pass, the export below is not attempted (as root it would
    # replace the machine's /dev/null)
    with pytest.raises(ExportError, match="character device"):
        _atomic.write_target("/dev/null", "STL file")
    with pytest.raises(ExportError, match="character device"):
        exporters.export_stl("/dev/null", primitives.box())
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


# -- symbolic links ---------------------------------------------------------------------------

@pytest.mark.parametrize("suffix, write", WRITERS, ids=WRITER_IDS)
def test_a_symbolic_link_is_kept_and_the_file_it_names_replaced(tmp_path, suffix, write):
    links, files = tmp_path / "links", tmp_path / "files"
    links.mkdir()
    files.mkdir()
    real = files / f"model{suffix}"
    real.write_bytes(b"old contents")
    real.chmod(0o640)
    inode = os.stat(real).st_ino
    link = links / f"link{suffix}"
    os.symlink(os.path.join("..", "files", real.name), link)  # a relative link
    assert write(link) == str(link)
    assert os.path.islink(link) and os.readlink(link) == os.path.join("..", "files", real.name)
    assert os.stat(real).st_ino != inode  # replaced by a rename (atomically), not rewritten in place
    assert stat.S_IMODE(os.stat(real).st_mode) == 0o640
    _read_back(real, suffix)
    assert sorted(os.listdir(files)) == [real.name] and sorted(os.listdir(links)) == [link.name]


def test_a_chain_of_links_and_a_dangling_link(tmp_path):
    real = tmp_path / "real.stl"
    real.write_bytes(b"old")
    os.symlink(real, tmp_path / "one.stl")
    os.symlink(tmp_path / "one.stl", tmp_path / "two.stl")
    _write_stl(tmp_path / "two.stl")
    assert os.path.islink(tmp_path / "two.stl") and os.path.islink(tmp_path / "one.stl")
    _read_back(real, ".stl")
    # a link to a file that does not exist yet creates that file, as open(link, "w") would
    os.symlink("made.obj", tmp_path / "dangling.obj")
    _write_obj(tmp_path / "dangling.obj")
    assert os.path.islink(tmp_path / "dangling.obj")
    _read_back(tmp_path / "made.obj", ".obj")
    # a link to a FIFO is refused like the FIFO
    os.mkfifo(tmp_path / "fifo")
    os.symlink(tmp_path / "fifo", tmp_path / "to-fifo.stl")
    with pytest.raises(ExportError, match="FIFO"):
        _write_stl(tmp_path / "to-fifo.stl")
    # a loop of links is an ExportError, not an OSError of the wrong type
    os.symlink(tmp_path / "loop-b.stl", tmp_path / "loop-a.stl")
    os.symlink(tmp_path / "loop-a.stl", tmp_path / "loop-b.stl")
    with pytest.raises(ExportError):
        _write_stl(tmp_path / "loop-a.stl")
    assert _temporaries(tmp_path) == []


# -- permissions ------------------------------------------------------------------------------

@pytest.mark.parametrize("suffix, write", WRITERS, ids=WRITER_IDS)
def test_a_replaced_file_keeps_its_permissions(tmp_path, suffix, write):
    target = tmp_path / f"kept{suffix}"
    target.write_bytes(b"old")
    target.chmod(0o604)
    write(target)
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o604
    _read_back(target, suffix)


def test_a_new_file_gets_the_umask_permissions(tmp_path):
    old = os.umask(0o027)
    try:
        _write_stl(tmp_path / "new.stl")
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(tmp_path / "new.stl").st_mode) == 0o640


@pytest.mark.skipif(IS_ROOT, reason="root may write read-only files")
def test_a_read_only_file_is_refused(tmp_path):
    target = tmp_path / "ro.stl"
    target.write_bytes(b"keep me")
    target.chmod(0o444)
    with pytest.raises(ExportError, match="read-only"):
        _write_stl(target)
    assert target.read_bytes() == b"keep me"


# -- error messages ---------------------------------------------------------------------------

@pytest.mark.skipif(IS_ROOT, reason="root ignores folder permissions")
@pytest.mark.parametrize("suffix, write", WRITERS, ids=WRITER_IDS)
def test_an_unwritable_folder_names_the_target_not_the_temporary_file(tmp_path, suffix, write):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        with pytest.raises(ExportError) as info:
            write(locked / f"m{suffix}")
    finally:
        locked.chmod(0o700)
    text = str(info.value)
    assert str(locked / f"m{suffix}") in text and _atomic.TEMP_PREFIX not in text
    assert os.listdir(locked) == []


@pytest.mark.parametrize("stage", ["mkstemp", "replace", "chmod"])
@pytest.mark.parametrize("suffix, write", WRITERS, ids=WRITER_IDS)
def test_os_errors_name_the_target_not_the_temporary_file(tmp_path, monkeypatch, stage, suffix, write):
    """Each OSError, as the OS reports it (with the temporary file's name), becomes an ExportError
    naming the target; runs as root too, where folder permissions cannot make it happen."""
    target = tmp_path / f"m{suffix}"
    target.write_bytes(b"old contents")
    if stage == "mkstemp":
        def fail(*args, dir=None, prefix="", suffix="", **kw):
            name = os.path.join(dir, prefix + "abcdefgh" + suffix)
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), name)

        monkeypatch.setattr(_atomic.tempfile, "mkstemp", fail)
    elif stage == "replace":
        def fail(src, dst):
            raise OSError(errno.EXDEV, os.strerror(errno.EXDEV), src, dst)

        monkeypatch.setattr(_atomic.os, "replace", fail)
    else:
        real_chmod = os.chmod

        def fail(path, mode, *a, **kw):  # just before the rename: the file is complete
            if os.path.basename(os.fspath(path)).startswith(_atomic.TEMP_PREFIX):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)
            return real_chmod(path, mode, *a, **kw)

        monkeypatch.setattr(_atomic.os, "chmod", fail)
    with pytest.raises(ExportError) as info:
        write(target)
    text = str(info.value)
    assert repr(str(target)) in text and _atomic.TEMP_PREFIX not in text, text
    assert target.read_bytes() == b"old contents"
    assert _temporaries(tmp_path) == []


@pytest.mark.parametrize("suffix, write", WRITERS, ids=WRITER_IDS)
def test_a_nul_byte_in_a_path_is_a_splinekit_error(tmp_path, suffix, write):
    with pytest.raises(ParameterError, match="NUL"):
        write(str(tmp_path / f"a\0b{suffix}"))
    with pytest.raises(SplineKitError, match="NUL"):
        write(os.fsencode(str(tmp_path / f"c\0d{suffix}")))
    assert os.listdir(tmp_path) == []


def test_atomic_write_itself(tmp_path):
    """The helper as plot.py and the exporters call it: the return value, a new file, a failure."""
    target = tmp_path / "x.bin"

    def fill(tmp):
        with open(tmp, "wb") as fh:
            fh.write(b"new")

    assert _atomic.atomic_write(target, fill) == str(target)
    assert target.read_bytes() == b"new"
    with pytest.raises(ParameterError, match="NUL"):
        _atomic.atomic_write(str(tmp_path / "a\0"), fill)
    with pytest.raises(ParameterError):
        _atomic.atomic_write("", fill)
    with pytest.raises(ParameterError):
        _atomic.atomic_write(3.5, fill)
    assert os.listdir(tmp_path) == ["x.bin"]
