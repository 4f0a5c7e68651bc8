"""tools/instr_bisect.py names the commit that slowed a job: a scratch repository of synthetic
commits, a trivial build and a measure that reads the figure a commit records, driven through the
real command (its scratch worktree, `git bisect run`, the threshold, the report)."""
import subprocess
import sys

import pytest

from conftest import ROOT

TOOL = ROOT / "tools" / "instr_bisect.py"

# (figure, subject): commit 4 adds 1 % (below the threshold: not the culprit), commit 7 adds 15 %
# (the one to find), commit 9 does not build (skipped if the bisect ever lands on it).
HISTORY = [(1000, "start"), (1000, "docs"), (1000, "refactor"), (1010, "tiny cost"), (1010, "tests"),
           (1010, "more tests"), (1160, "slower loop"), (1160, "cleanup"), (None, "broken build"),
           (1160, "fix build"), (1160, "tip")]


def git(repo, *args):
    return subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True, text=True).stdout.strip()


@pytest.fixture()
def repo(tmp_path):
    r = tmp_path / "proj"
    r.mkdir()
    git(r, "init", "-q", "-b", "main")
    git(r, "config", "user.email", "t@example.org")
    git(r, "config", "user.name", "t")
    shas = []
    for i, (fig, subject) in enumerate(HISTORY):
        (r / "work.txt").write_text(f"{fig if fig is not None else 'x'}\n")
        (r / "build.sh").write_text("grep -qv x work.txt\n")  # the broken commit does not build
        (r / "n.txt").write_text(f"{i}\n")
        git(r, "add", ".")
        git(r, "commit", "-q", "-m", subject)
        shas.append(git(r, "rev-parse", "HEAD"))
    return r, shas


def bisect(repo, good, bad, work, *extra):
    return subprocess.run([sys.executable, str(TOOL), "--repo", str(repo), "--good", good, "--bad", bad, "--job", "j",
                           "--work", str(work), "--build-cmd", "sh build.sh", "--measure-cmd", "cat work.txt", *extra],
                          capture_output=True, text=True, timeout=300)


def test_bisect_names_the_commit_that_slowed_the_job(repo, tmp_path):
    r, shas = repo
    p = bisect(r, shas[0], shas[-1], tmp_path / "work")
    assert p.returncode == 0, p.stdout + p.stderr
    assert f"first bad commit: {shas[6]} slower loop" in p.stdout
    assert "1,000.000 at good -> 1,160.000 at bad (+16.00%)" in p.stdout
    # the checkout and branch are untouched, the scratch worktree is gone
    assert git(r, "rev-parse", "HEAD") == shas[-1]
    assert git(r, "worktree", "list").count("\n") == 0
    assert not (tmp_path / "work" / "src").exists()


def test_a_lower_threshold_names_the_small_step(repo, tmp_path):
    r, shas = repo
    p = bisect(r, shas[0], shas[5], tmp_path / "work", "--threshold", "0.005")
    assert p.returncode == 0, p.stdout + p.stderr
    assert f"first bad commit: {shas[3]} tiny cost" in p.stdout


def test_nothing_moved_is_said_and_exits_1(repo, tmp_path):
    r, shas = repo
    p = bisect(r, shas[0], shas[5], tmp_path / "work")
    assert p.returncode == 1
    assert "+1.00% from good to bad, within --threshold 3%: nothing to bisect" in p.stdout


def test_bad_input_exits_2(repo, tmp_path):
    r, shas = repo
    assert bisect(r, "no-such-ref", shas[-1], tmp_path / "w").returncode == 2
    assert bisect(r, shas[-1], shas[0], tmp_path / "w").returncode == 2  # good after bad
