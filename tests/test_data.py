"""Finding the real datasets by name: lookup order, errors, and downloads (never real ones)."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import pooch
import pytest
import requests

from fhslam import datasets as data
from fhslam.datasets import (
    DATASETS,
    Dataset,
    DatasetNotFoundError,
    find_dataset,
    is_held_out,
    verify,
)
from fhslam.errors import InputError

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"

FAKE_LOG = b"FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 1.0 host 1.0\n"
FAKE_REL = b"1.0 2.0 0.1 0 0 0 0 0\n"


@pytest.fixture(autouse=True)
def _no_network(monkeypatch):
    """No test may reach pooch's downloader; those that expect a call replace this."""

    def refuse(*args, **kwargs):
        raise AssertionError(f"pooch.retrieve called: {args} {kwargs}")

    monkeypatch.setattr(pooch, "retrieve", refuse)


@pytest.fixture
def fake(monkeypatch, tmp_path):
    """A registry entry 'fake' whose files are tiny, and an isolated working directory.

    Layout: tmp/work/repo is the working directory, tmp/work/shared/data is its
    ../shared/data, tmp/env is for $FHSLAM_DATA.
    """
    log = data.DataFile(
        "fake.clf",
        "https://example.invalid/fake.clf",
        len(FAKE_LOG),
        hashlib.sha256(FAKE_LOG).hexdigest(),
    )
    rel = data.DataFile(
        "fake.relations",
        "https://example.invalid/fake.relations",
        len(FAKE_REL),
        hashlib.sha256(FAKE_REL).hexdigest(),
    )
    monkeypatch.setitem(DATASETS, "fake", Dataset("fake", log, rel, held_out=False))
    repo = tmp_path / "work" / "repo"
    repo.mkdir(parents=True)
    monkeypatch.chdir(repo)
    monkeypatch.delenv(data.ENV_VAR, raising=False)
    return tmp_path


def _put(folder: Path, name: str, content: bytes) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(content)
    return folder / name


def test_registry_matches_design():
    assert set(DATASETS) == {
        "intel", "aces", "fr079", "fr-clinic", "mit-csail", "mit-killian", "fr101",
        "mit-killian-full",
    }  # fmt: skip
    assert not any(is_held_out(n) for n in DATASETS)  # all are development data
    assert DATASETS["intel"].log.name == "intel.orig.bag"
    assert DATASETS["mit-csail"].log.name == "mit-csail.clf"
    assert DATASETS["fr-clinic"].log.name == "fr-clinic_robotlaser.orig.bag"
    assert DATASETS["mit-killian"].log is None
    base = f"https://raw.githubusercontent.com/INESCTEC/ricoslam/{data.SOURCE_COMMIT}/"
    base += "inesctec_mrdt_slam_2d_datasets/"
    for ds in DATASETS.values():
        for _, f in ds.files():
            folder = "bag" if f.name.endswith(".bag") else "data"
            if f.url == "":  # relations derived for this benchmark: no upstream copy
                assert f.name.endswith(".relations") and ds.name in ("fr101", "mit-killian-full")
            elif f.name == "fr101.carmen.log.gz":
                assert f.url.endswith("/MapFiles/fr101.carmen.log.gz")
            else:
                assert f.url == base + folder + "/" + f.name
            assert re.fullmatch(r"[0-9a-f]{64}", f.sha256)


def test_registry_matches_sources_md():
    sources = SHARED / "SOURCES.md"
    if not sources.is_file():
        pytest.skip(f"no {sources} to compare the registry with")
    rows = {}
    for line in sources.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 4 and cells[1].startswith("inesctec_mrdt_slam_2d_datasets/"):
            rows[cells[0].removeprefix("data/")] = (cells[1], int(cells[2]), cells[3])
    files = [  # the files of the source's table (the others have their own rows)
        f
        for ds in DATASETS.values()
        for _, f in ds.files()
        if "ricoslam" in f.url and "clf2bag" not in f.name
    ]
    assert {f.name for f in files} == set(rows)
    for f in files:
        path, size, sha = rows[f.name]
        assert f.url.endswith("/" + path)
        assert (f.size, f.sha256) == (size, sha)


def test_unknown_name_lists_known_names():
    with pytest.raises(ValueError, match="unknown dataset 'nope'") as e:
        find_dataset("nope")
    for name in DATASETS:
        assert name in str(e.value)
    with pytest.raises(ValueError, match="intel"):
        is_held_out("nope")


def test_bad_kind_and_missing_log():
    with pytest.raises(ValueError, match="kind"):
        find_dataset("intel", kind="map")
    with pytest.raises(InputError, match=r"dataset 'mit-killian' has only relations"):
        find_dataset("mit-killian", kind="log")


def test_a_dataset_of_relations_only_is_no_log(monkeypatch):
    """``fhslam info mit-killian`` (slam, bench --log) is an InputError, not a traceback
    (``ValueError: dataset 'mit-killian' has no log file``), saying what the dataset has and
    what it is for (its relations are still found)."""
    from fhslam.datasets import load_log

    with pytest.raises(InputError) as e:
        load_log("mit-killian")
    assert str(e.value) == (
        "dataset 'mit-killian' has only relations (mit-killian.relations), no laser log to "
        "read; they evaluate a trajectory: fhslam evaluate TRAJECTORY --relations mit-killian"
    )
    assert DATASETS["mit-killian"].file("relations").name == "mit-killian.relations"


def test_explicit_path_wins(fake, monkeypatch):
    explicit = _put(fake / "elsewhere", "my.clf", b"anything at all")
    monkeypatch.setenv(data.ENV_VAR, str(_put(fake / "env", "fake.clf", FAKE_LOG).parent))
    assert find_dataset(explicit) == explicit
    assert find_dataset(str(explicit), kind="relations") == explicit


def test_missing_explicit_path_is_not_found(fake):
    with pytest.raises(DatasetNotFoundError, match="no such file"):
        find_dataset(fake / "missing.clf")


def test_env_wins_over_shared_data(fake, monkeypatch):
    shared = _put(fake / "work" / "shared" / "data", "fake.clf", FAKE_LOG)
    assert find_dataset("fake") == shared
    env = _put(fake / "env", "fake.clf", FAKE_LOG)
    monkeypatch.setenv(data.ENV_VAR, str(env.parent))
    assert find_dataset("fake") == env


def test_env_without_the_file_falls_through(fake, monkeypatch):
    (fake / "env").mkdir()
    monkeypatch.setenv(data.ENV_VAR, str(fake / "env"))
    shared = _put(fake / "work" / "shared" / "data", "fake.relations", FAKE_REL)
    assert find_dataset("fake", kind="relations") == shared


def test_shared_data_beside_an_ancestor_of_the_cwd(fake, monkeypatch):
    shared = _put(fake / "work" / "shared" / "data", "fake.clf", FAKE_LOG)
    deep = fake / "work" / "repo" / "notebooks" / "sub"
    deep.mkdir(parents=True)
    monkeypatch.chdir(deep)
    assert find_dataset("fake") == shared


def test_file_name_selects_dataset_and_kind(fake):
    shared = _put(fake / "work" / "shared" / "data", "fake.relations", FAKE_REL)
    assert find_dataset("fake.relations") == shared


def test_size_mismatch_is_a_value_error(fake, monkeypatch, recwarn):
    env = _put(fake / "env", "fake.clf", b"version https://git-lfs.github.com/spec/v1\n")
    monkeypatch.setenv(data.ENV_VAR, str(env.parent))
    with pytest.raises(ValueError, match=re.escape(str(env))):
        find_dataset("fake")
    assert len(recwarn) == 0


def test_not_found_lists_places_and_fixes(fake, monkeypatch):
    monkeypatch.setattr(data, "__file__", str(fake / "site" / "pkg" / "fhslam" / "datasets.py"))
    with pytest.raises(DatasetNotFoundError) as e:
        find_dataset("fake", kind="relations")
    msg = str(e.value)
    assert isinstance(e.value, FileNotFoundError)
    assert "fake.relations" in msg
    assert "$FHSLAM_DATA (not set)" in msg
    for _, d in data.search_dirs():
        assert str(d / "fake.relations") in msg
    assert str(fake / "work" / "shared" / "data" / "fake.relations") in msg
    assert str(fake / "site" / "shared" / "data" / "fake.relations") in msg
    assert "download=True" in msg and "--download" in msg

    monkeypatch.setenv(data.ENV_VAR, str(fake / "env"))
    with pytest.raises(DatasetNotFoundError, match=re.escape(str(fake / "env" / "fake.relations"))):
        find_dataset("fake", kind="relations")


def test_no_download_never_calls_pooch(fake):
    # the autouse fixture makes any pooch.retrieve call fail the test
    with pytest.raises(DatasetNotFoundError):
        find_dataset("fake")
    with pytest.raises(DatasetNotFoundError):
        verify("fake")


def test_download_calls_pooch_with_url_and_hash(fake, monkeypatch):
    calls = []
    cached = _put(fake / "cache", "fake.clf", FAKE_LOG)

    def retrieve(url, known_hash=None, fname=None, path=None, **kwargs):
        calls.append((url, known_hash, fname, path))
        return str(cached)

    monkeypatch.setattr(pooch, "retrieve", retrieve)
    assert find_dataset("fake", download=True) == cached
    f = DATASETS["fake"].log
    assert calls == [(f.url, "sha256:" + f.sha256, "fake.clf", pooch.os_cache("fhslam"))]


def test_download_of_a_real_entry_uses_its_github_url(fake, monkeypatch):
    seen = {}

    def retrieve(url, known_hash=None, **kwargs):
        seen.update(url=url, known_hash=known_hash)
        return str(fake / "whatever")

    monkeypatch.setattr(data, "__file__", str(fake / "site" / "pkg" / "fhslam" / "datasets.py"))
    monkeypatch.setattr(pooch, "retrieve", retrieve)
    got = find_dataset("aces", kind="relations", download=True)
    assert seen, f"not downloaded: found {got}"
    assert seen == {
        "url": "https://raw.githubusercontent.com/INESCTEC/ricoslam/"
        "52bfaa91c8e5e56f119265d409b1692ca29d48d2/"
        "inesctec_mrdt_slam_2d_datasets/data/aces.relations",
        "known_hash": "sha256:11a15800a751b6f9413078a021d49c7cda85a768c2a465433b4fae7ef57b03d5",
    }


DOWNLOAD_FAILURES = [
    requests.exceptions.ConnectionError(
        "HTTPSConnectionPool(host='raw.githubusercontent.com', port=443): Max retries "
        "exceeded\n(Caused by NameResolutionError)"
    ),
    OSError(28, "No space left on device"),
    ValueError(
        "SHA256 hash of downloaded file (intel.orig.bag) does not match the known hash: "
        "expected sha256:b37c but got 0000. Deleted download for safety."
    ),
]


def _failing_retrieve(monkeypatch, error: Exception) -> list:
    """Make pooch.retrieve raise ``error``; the list returned records each call's URL."""
    calls = []

    def retrieve(url, *args, **kwargs):
        calls.append(url)
        raise error

    monkeypatch.setattr(pooch, "retrieve", retrieve)
    return calls


@pytest.mark.parametrize("error", DOWNLOAD_FAILURES, ids=["connection", "oserror", "sha256"])
def test_failed_download_names_the_dataset_file_url_and_cause(fake, monkeypatch, error):
    calls = _failing_retrieve(monkeypatch, error)
    f = DATASETS["fake"].log
    with pytest.raises(DatasetNotFoundError) as e:
        find_dataset("fake", download=True)
    assert calls == [f.url]
    assert isinstance(e.value, InputError) and e.value.__cause__ is error
    msg = str(e.value)
    assert msg.startswith(f"could not download fake.clf for dataset 'fake' from {f.url}: ")
    assert " ".join(str(error).split()) in msg and "\n" not in msg
    assert "$FHSLAM_DATA" in msg


@pytest.mark.parametrize("error", DOWNLOAD_FAILURES, ids=["connection", "oserror", "sha256"])
def test_failed_download_is_a_one_line_cli_error(tmp_path, monkeypatch, capsys, error):
    """`fhslam slam intel --download` with the download failing: exit status 2 and one line
    naming the dataset, the file and the URL; no traceback, no output. No local copy is
    found even where the shared data folder exists, and the network is never touched."""
    from fhslam.cli import main

    empty = tmp_path / "empty"
    empty.mkdir()
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv(data.ENV_VAR, str(empty))
    monkeypatch.setattr(data, "search_dirs", lambda: [(f"${data.ENV_VAR}", empty)])
    calls = _failing_retrieve(monkeypatch, error)
    out = tmp_path / "t.txt"
    assert main(["slam", "intel", "--download", "--trajectory", str(out), "--quiet"]) == 2
    f = DATASETS["intel"].log
    assert calls == [f.url]  # the download was tried, and failed
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("fhslam: error: could not download intel.orig.bag for ")
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    assert "dataset 'intel'" in captured.err and f.url in captured.err
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["empty"]


def test_verify_checks_sha256(fake, monkeypatch):
    shared = fake / "work" / "shared" / "data"
    log = _put(shared, "fake.clf", FAKE_LOG)
    rel = _put(shared, "fake.relations", FAKE_REL)
    assert verify("fake") == {"log": log, "relations": rel}
    _put(shared, "fake.relations", FAKE_REL.replace(b"0.1", b"0.2"))  # same size, other bytes
    with pytest.raises(ValueError, match="sha256"):
        verify("fake")


@pytest.fixture
def real_shared():
    if not (SHARED / "intel.orig.bag").is_file():
        pytest.skip(f"no real data in {SHARED}: the Freiburg logs are not shipped with fhslam")
    return SHARED


def test_real_intel_is_found(real_shared, monkeypatch):
    monkeypatch.delenv(data.ENV_VAR, raising=False)
    assert find_dataset("intel") == real_shared / "intel.orig.bag"
    assert find_dataset("intel", kind="relations") == real_shared / "intel.relations"


def test_real_mit_csail_verifies(real_shared, monkeypatch):
    if not (real_shared / "mit-csail.clf").is_file():
        pytest.skip(f"no mit-csail.clf in {real_shared}")
    monkeypatch.delenv(data.ENV_VAR, raising=False)
    found = verify("mit-csail")
    assert found == {
        "log": real_shared / "mit-csail.clf",
        "relations": real_shared / "mit-csail.relations",
    }
    # the hashes recorded in SOURCES.md, independently of the registry
    expected = {
        "log": "f40f31cf9e561cb2a0cb0ca2f4a809abb319543cd1b2875f6c8c6a0138559ca4",
        "relations": "ffd7ebe97fa1738913931e39ca643ee0a1b67de80499b0197a3d01abad0f589d",
    }
    for kind, path in found.items():
        assert hashlib.sha256(path.read_bytes()).hexdigest() == expected[kind]
