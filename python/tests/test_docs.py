"""What README.md, the guide (docs/*.md) and the examples gallery
(examples/README.md) show, the program does.

Every ```console block is run, command by command, in a scratch folder that
looks like a clone's root (scenarios/ and examples/ in it), with `mrsim` the
release build and `cargo run --release [--example NAME] [-- ARGS]` the built
binaries (the commands are run as printed, with bash). A command is a line
starting with `$ ` (continued by a trailing backslash); a command ending in
` &` runs in the background, beside the block's next commands, and is waited
for at the end of the block. The lines after a command, up to the next, are
what the text says it prints: each must be found in a line of the command's
output (stdout and stderr), with `...` standing for anything and runs of
spaces counted as one space; a line `[exit status N]` says how it ends (0
otherwise). A command whose comment starts with `# long` is run only with
MRSIM_DOCS_LONG=1.

The other fenced blocks (```sh and the rest) show synopses and commands for
several terminals or hosts; of those, every scenario file a `mrsim` command
names must exist. Every relative link (a file, and an `#anchor` in a
Markdown file) must point at something that exists.
"""

import os
import re
import shlex
import subprocess
import sys

import pytest

from conftest import built_mrsim

REPO = __import__("conftest").REPO

#: The documents whose commands and links are checked.
DOCS = sorted(
    [REPO / "README.md", REPO / "examples" / "README.md", *(REPO / "docs").glob("*.md")]
)


def fenced_blocks(path):
    """Every fenced block of `path`: (language, first line number, lines)."""
    blocks, lang, start, body, indent = [], None, 0, [], ""
    for n, line in enumerate(path.read_text().split("\n"), 1):
        if lang is None:
            m = re.match(r"^(\s*)```(\S*)\s*$", line)
            if m:
                indent, lang, start, body = m.group(1), m.group(2), n + 1, []
        elif line.strip().startswith("```"):
            blocks.append((lang, start, body))
            lang = None
        else:
            # A block in a list item: its lines indented as its fence.
            body.append(line[len(indent) :] if line.startswith(indent) else line)
    assert lang is None, f"{path}: a block opened at line {start - 1} is not closed"
    return blocks


class Command:
    """One `$ ` line of a console block and what the text says it prints."""

    def __init__(self, where, text):
        self.where, self.text, self.expected, self.status = where, text, [], 0

    @property
    def background(self):
        return self.code().endswith("&")

    @property
    def long(self):
        return bool(re.search(r"#\s*long\b", self.text))

    def code(self):
        """The command without its trailing comment (a `#` after a space)."""
        return re.sub(r"(^|\s)#\s.*$", "", self.text).strip()


def console_commands(path, start, lines):
    commands, pending = [], None
    for i, line in enumerate(lines):
        where = f"{path.relative_to(REPO)}:{start + i}"
        if pending is not None:
            pending.text += "\n" + line
            if not line.rstrip().endswith("\\"):
                pending = None
            continue
        if line.startswith("$ "):
            commands.append(Command(where, line[2:]))
            if line.rstrip().endswith("\\"):
                pending = commands[-1]
        elif line.strip() and commands:
            m = re.fullmatch(r"\[exit status (\d+)\]", line.strip())
            if m:
                commands[-1].status = int(m.group(1))
            elif line.strip() != "...":
                commands[-1].expected.append(line)
        elif line.strip():
            raise AssertionError(f"{where}: output before any command: {line!r}")
    return commands


def console_blocks(path):
    """The commands of each ```console block of `path`, in order."""
    return [
        console_commands(path, start, lines)
        for lang, start, lines in fenced_blocks(path)
        if lang == "console"
    ]


def squeeze(s):
    return " ".join(s.split())


def found(expected, output):
    """Whether a line of `output` holds `expected`'s parts, `...` between them."""
    parts = [squeeze(p) for p in squeeze(expected).split("...")]
    for line in output.split("\n"):
        line, at = squeeze(line), 0
        for p in parts:
            at = line.find(p, at)
            if at < 0:
                break
            at += len(p)
        else:
            return True
    return False


CARGO_SHIM = """#!/bin/sh
# `cargo run --release [--example NAME] [-- ARGS]`: the binaries the tests built.
[ "$1" = run ] && [ "$2" = --release ] || { echo "cargo shim: only cargo run --release" >&2; exit 99; }
shift 2
bin={target}/mrsim
if [ "$1" = --example ]; then bin={target}/examples/$2; shift 2; fi
[ "$1" = -- ] && shift
exec "$bin" "$@"
"""


@pytest.fixture
def clone(tmp_path):
    """A scratch clone root and the PATH that finds `mrsim` and `cargo` there."""
    exe = built_mrsim(REPO)
    for name in ["scenarios", "examples"]:
        (tmp_path / name).symlink_to(REPO / name)
    bin_dir = tmp_path.parent / f"{tmp_path.name}-bin"
    bin_dir.mkdir()
    (bin_dir / "mrsim").symlink_to(exe)
    shim = bin_dir / "cargo"
    shim.write_text(CARGO_SHIM.replace("{target}", shlex.quote(os.path.dirname(exe))))
    shim.chmod(0o755)
    # A script, not a link: a link outside the virtualenv's bin/ would start
    # the interpreter without the virtualenv's packages.
    py = bin_dir / "python"
    py.write_text(f"#!/bin/sh\nexec {shlex.quote(sys.executable)} \"$@\"\n")
    py.chmod(0o755)
    env = dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ['PATH']}")
    env.setdefault("MRSIM_PROGRESS", "off")
    return tmp_path, env


def check(cmd, status, output):
    """What is wrong with a command's outcome (None: what the text says)."""
    if status != cmd.status:
        return (
            f"{cmd.where}: `{cmd.text}` ended with status {status}, "
            f"the text says {cmd.status}:\n{output}"
        )
    for line in cmd.expected:
        if not found(line, output):
            return (
                f"{cmd.where}: `{cmd.text}`: the text says it prints\n  {line}\n"
                f"but it printed:\n{output}"
            )
    return None


def run_block(commands, cwd, env):
    """Runs one block's commands; what went wrong, one message each."""
    wrong, background = [], []
    try:
        for cmd in commands:
            code = cmd.code()
            if cmd.background:
                proc = subprocess.Popen(
                    ["bash", "-c", code[:-1]], cwd=cwd, env=env, text=True,
                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                )  # fmt: skip
                background.append((cmd, proc))
                continue
            done = subprocess.run(
                ["bash", "-c", code], cwd=cwd, env=env, text=True, timeout=600,
                stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            )  # fmt: skip
            wrong.append(check(cmd, done.returncode, done.stdout))
        for cmd, proc in background:
            output, _ = proc.communicate(timeout=300)
            wrong.append(check(cmd, proc.returncode, output))
    finally:
        for _, proc in background:
            proc.kill()
    return [w for w in wrong if w]


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: str(p.relative_to(REPO)))
def test_every_console_command_of_the_docs_prints_what_the_text_says(doc, clone):
    """A document's blocks run in order in one folder (a later block may read
    the run folder an earlier one wrote, as a reader would)."""
    cwd, env = clone
    long = os.environ.get("MRSIM_DOCS_LONG") == "1"
    wrong, skipped = [], []
    for commands in console_blocks(doc):
        if any(c.long for c in commands) and not long:
            skipped += [c.where for c in commands]
            continue
        wrong += run_block(commands, cwd, env)
    if skipped:
        print(f"not run (long; MRSIM_DOCS_LONG=1 runs them): {', '.join(skipped)}")
    assert not wrong, "\n\n".join(wrong)


def test_the_readme_and_the_gallery_have_console_blocks_to_run():
    for doc in [REPO / "README.md", REPO / "examples" / "README.md"]:
        blocks = console_blocks(doc)
        assert len(blocks) >= 5, (doc, len(blocks))
        assert all(blocks), f"{doc}: a console block without a command"


def shown_commands():
    """The `mrsim` commands of the blocks that are not run: (where, words)."""
    out = []
    for path in DOCS:
        for lang, start, lines in fenced_blocks(path):
            if lang == "console":
                continue
            for i, line in enumerate(lines):
                words = line.split("#")[0].split()
                if words[:1] == ["mrsim"]:
                    out.append((f"{path.relative_to(REPO)}:{start + i}", words))
    return out


def test_every_scenario_a_shown_command_names_exists():
    seen = 0
    for where, words in shown_commands():
        for w in words[2:]:
            w = w.strip("'\"")
            if w.endswith(".toml") and not w.startswith("--"):
                seen += 1
                assert (REPO / w).is_file(), f"{where}: {w} is not in the repository"
    assert seen >= 5, seen


def anchors(path):
    """GitHub's anchors of a Markdown file's headings."""
    out, fence = set(), False
    for line in path.read_text().split("\n"):
        if line.strip().startswith("```"):
            fence = not fence
        m = None if fence else re.match(r"^#{1,6}\s+(.*?)\s*$", line)
        if m:
            slug = re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-")
            base, n = slug, 1
            while slug in out:
                slug, n = f"{base}-{n}", n + 1
            out.add(slug)
    return out


def links(path):
    """Every relative link target of `path` outside code: (line, target)."""
    out, fence = [], False
    for n, line in enumerate(path.read_text().split("\n"), 1):
        if line.strip().startswith("```"):
            fence = not fence
            continue
        if fence:
            continue
        line = re.sub(r"`[^`]*`", "", line)
        for target in re.findall(r"\]\(([^)\s]+)\)", line):
            if not re.match(r"^[a-z]+:", target):
                out.append((n, target))
    return out


def test_every_relative_link_of_the_docs_points_at_a_file_and_anchor_that_exist():
    checked = 0
    for path in [*DOCS, REPO / "ARCHITECTURE.md"]:
        for n, target in links(path):
            file, _, anchor = target.partition("#")
            dest = (path.parent / file).resolve() if file else path
            where = f"{path.relative_to(REPO)}:{n}"
            assert dest.exists(), f"{where}: {target}: no such file"
            if anchor:
                assert dest.suffix == ".md", f"{where}: {target}: an anchor in a non-Markdown file"
                assert anchor in anchors(dest), f"{where}: {target}: no such heading"
            checked += 1
    assert checked >= 20, checked
