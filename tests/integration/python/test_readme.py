"""Every code block of the README runs as a user would run it, from the
repository's root, and says nothing a user would read as a problem: no
warning, no error, no traceback. The Python example prints the numbers its
comment promises, to the comment's digits.

The block of the two commands runs its first (`bash fmu/main.sh`); its second
is the command that runs this test.
"""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
README = ROOT / "README.md"
PROBLEM = re.compile(r"warning|error|traceback|deprecat", re.IGNORECASE)
# The command that runs the whole test suite, this test among them.
ITSELF = "bash tests/run.sh"


def blocks():
    """(language, text, first line number) of each fenced block."""
    found, language, lines, start = [], None, [], 0
    for number, line in enumerate(README.read_text(encoding="utf-8").splitlines(), 1):
        if line.startswith("```"):
            if language is None:
                language, lines, start = line[3:].strip() or "text", [], number
            else:
                found.append((language, "\n".join(lines), start))
                language = None
        elif language is not None:
            lines.append(line)
    return found


def commands(text):
    """The shell block's commands, their trailing comments dropped."""
    out = []
    for line in text.splitlines():
        command = re.sub(r"\s+#.*$", "", line).strip()
        if command and not command.startswith("#"):
            out.append(command)
    return out


def problems(output):
    return [line for line in output.splitlines() if PROBLEM.search(line)]


BLOCKS = blocks()


def test_the_readme_has_its_blocks():
    languages = [language for language, _, _ in BLOCKS]
    assert languages.count("python") >= 1 and languages.count("sh") >= 2, languages


@pytest.mark.parametrize("language,text,line", BLOCKS, ids=[f"line{line}-{lang}" for lang, _, line in BLOCKS])
def test_a_readme_block_runs_without_a_warning(language, text, line):
    if language == "python":
        run = subprocess.run([sys.executable, "-c", text], cwd=ROOT, capture_output=True, text=True, timeout=900)
        output = run.stdout + run.stderr
        assert run.returncode == 0, f"README line {line}:\n{output[-3000:]}"
        assert not problems(output), f"README line {line} prints:\n" + "\n".join(problems(output))
        # "# about 7.71 pli at 300.3 m/min": the printed numbers, to the comment's digits.
        promised = re.search(r"print\(.*#\s*about\s+(.*)$", text, re.M)
        if promised:
            expected = re.findall(r"\d+\.\d+", promised.group(1))
            printed = re.findall(r"[-\d.e+]+", run.stdout.strip().splitlines()[-1])
            got = [float(x) for x in printed if re.fullmatch(r"-?\d+(\.\d+)?(e[-+]?\d+)?", x)]
            assert len(got) == len(expected), (run.stdout, expected)
            for g, e in zip(got, expected):
                digits = len(e.split(".")[1])
                assert round(g, digits) == float(e), f"README line {line}: printed {g}, the comment says {e}"
        return
    assert language == "sh", f"README line {line}: a {language} block the test does not know how to run"
    for command in commands(text):
        if command == ITSELF:
            continue
        run = subprocess.run(["bash", "-c", command], cwd=ROOT, capture_output=True, text=True, timeout=1800)
        output = run.stdout + run.stderr
        assert run.returncode == 0, f"README line {line}: {command}\n{output[-3000:]}"
        assert not problems(output), f"README line {line}: {command} prints:\n" + "\n".join(problems(output))


def test_the_readme_states_the_prerequisites_the_clean_machine_check_installs():
    """tests/clean_machine.sh installs on a clean Debian 12 root exactly the Debian packages the
    README names as prerequisites, and nothing else: what it passes with, the README promises."""
    script = (ROOT / "tests" / "clean_machine.sh").read_text()
    installed = re.search(r"^PREREQUISITES=\(([^)]*)\)", script, re.M).group(1).split()
    paragraph = re.search(r"\*\*Prerequisites:\*\*(.*?)(?:\n\n|Everything else)", README.read_text(encoding="utf-8"), re.S).group(1)
    named = re.findall(r"`([a-z0-9.+-]+)`", paragraph)
    assert sorted(named) == sorted(installed), (named, installed)
