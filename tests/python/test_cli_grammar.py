"""One grammar across the command line, checked over every command's --help.

- `trueaxis help` lists every command; every command and sub-command takes --help and --version.
- --axis, wherever a command has it, is a machine axis (x|y|z) and takes X as x.
- Flags that name what a command writes (-o/--output, --report, --log, --truth, --csv, --points,
  --corrected-design) are never read as inputs (an input option shows FILE or DIR in the help).
- A command that writes a file has -o/--output for it (its main output).
- Units are written one way: µm, µrad, °C (never "um", "urad", "deg C").
"""
import os
import re
import subprocess

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")

# Named outputs: what each of these flags names is written, never read.
OUTPUT_FLAGS = {"--output", "--report", "--log", "--truth", "--csv", "--points", "--corrected-design"}
# Commands with no file of their own to name with -o: a server, a client that prints, the help.
NO_OUTPUT = {"serve", "ipp check", "ipp run", "help"}


def run(*args):
    return subprocess.run([TRUEAXIS, *args], capture_output=True, text=True, timeout=60)


def subcommands(help_text):
    """The command names a --help lists under 'Subcommands:' (first word of each entry)."""
    if "Subcommands:" not in help_text:
        return []
    names = []
    for line in help_text.split("Subcommands:", 1)[1].splitlines():
        m = re.match(r"^  (\S+)\s{2,}\S", line)
        if m:
            names.append(m.group(1))
    return names


def every_command():
    """Every command path, e.g. ('simulate', 'part'), found from the help alone."""
    top = run("help").stdout
    names = [m.group(1) for m in re.finditer(r"^  (\S+)\s{2,}\S", top, re.M)]
    assert len(names) >= 20, top
    out, todo = [], [(n,) for n in names]
    while todo:
        path = todo.pop(0)
        out.append(path)
        todo += [path + (s,) for s in subcommands(run(*path, "--help").stdout)]
    return out


COMMANDS = every_command()


def options(help_text):
    """{long flag: the text of its line} from a --help's option list."""
    found = {}
    for line in help_text.splitlines():
        m = re.match(r"^\s+(-\w,)?(--[\w-]+)(?:,[-\w,]+)?\s+(.*)$", line)
        if m:
            found[m.group(2)] = line
    return found


def test_every_command_takes_help_and_version():
    assert ("simulate", "part") in COMMANDS and ("export", "fanuc") in COMMANDS
    for path in COMMANDS:
        h = run(*path, "--help")
        assert h.returncode == 0, (path, h.stderr)
        v = run(*path, "--version")
        assert v.returncode == 0 and v.stdout.startswith("trueaxis "), (path, v.stdout, v.stderr)


def test_axis_is_a_machine_axis_everywhere():
    with_axis = [p for p in COMMANDS if "--axis " in run(*p, "--help").stdout]
    assert len(with_axis) >= 6, with_axis
    for path in with_axis:
        line = options(run(*path, "--help").stdout)["--axis"]
        assert "x|y|z" in line, (path, line)
        bad = run(*path, "--axis", "w")
        assert bad.returncode == 2 and "not a machine axis" in bad.stderr, (path, bad.stderr)


def test_outputs_are_never_inputs_and_writers_have_dash_o():
    for path in COMMANDS:
        text = run(*path, "--help").stdout
        if subcommands(text):
            continue
        opts = options(text)
        for flag in OUTPUT_FLAGS & opts.keys():
            assert ":FILE" not in opts[flag] and ":DIR" not in opts[flag], (path, opts[flag])
        writes = OUTPUT_FLAGS & opts.keys()
        if writes and " ".join(path) not in NO_OUTPUT:
            assert "--output" in opts and "-o," in opts["--output"], (path, sorted(writes))


def test_units_are_written_one_way():
    texts = [run("help").stdout] + [run(*p, "--help").stdout for p in COMMANDS]
    for path, text in zip([("help",)] + COMMANDS, texts):
        assert not re.search(r"(?<![\w])(um|urad)(?![\w])", text), (path, re.findall(r".{30}\bum\b.{10}", text))
        assert "deg C" not in text, path
