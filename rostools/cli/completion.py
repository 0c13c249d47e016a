"""``rostools completion show|install SHELL``, and the generators behind ``completions/``.

``build_tree`` walks the Typer app into ``tree.json``: every group, command and option, and
the kind of value each argument takes (a topic, a node, a bag file, ...). ``script`` renders
the bash, zsh and fish glue that hands the command line to ``rostools __complete`` (see
``rostools.cli.completer``). Both are checked in; a test fails when they are stale
(``python -m rostools.cli.completion`` rewrites them).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.output import Format, emit
from rostools.errors import UsageError

app = typer.Typer(
    name="completion",
    help="Shell completion for bash, zsh and fish: show or install the script.",
    no_args_is_help=True,
    add_completion=False,
)

SHELLS = ("bash", "zsh", "fish")
ROOT = Path(__file__).resolve().parent.parent.parent
SCRIPT_NAMES = {"bash": "rostools.bash", "zsh": "_rostools", "fish": "rostools.fish"}

#: The kind of value an argument or option takes, by name; ``(group, [command,] name)`` wins.
KINDS: dict[tuple[str, ...] | str, str] = {
    "topic": "topic",
    "topics": "topic",
    "service": "service",
    "node": "node",
    "nodes": "node",
    "msg_type": "msg",
    "srv_type": "srv",
    "type_name": "type",
    "bags": "files bag mcap active",
    "bag": "files bag mcap active",
    "src": "files bag mcap active",
    "dst": "files",
    "file": "files",
    "textfile": "files",
    "binfile": "files",
    "output_dir": "dirs",
    "msg_paths": "dirs",
    "exclude": "",
    ("topic", "namespace"): "topic",
    ("service", "namespace"): "service",
    ("param", "namespace"): "param",
    ("param", "name"): "param",
    ("param", "file"): "files yaml",
    ("node", "namespace"): "node",
    ("topic", "echo", "topic"): "topic_field",
    ("topic", "type", "topic"): "topic_field",
    ("topic", "msg_type"): "topic_type",
    ("topic", "args"): "message",
    ("service", "values"): "request",
    ("action", "action"): "action",
    ("action", "goal"): "goal",
    ("log", "logger"): "logger",
    ("log", "level"): "choice:debug,info,warn,error,fatal",
    ("log", "echo", "node_filter"): "node",
    ("tf", "source"): "frame",
    ("tf", "target"): "frame",
    ("bag", "topics"): "",
    ("bag", "record", "topics"): "topic",
    ("bag", "to"): "choice:ros1,ros2",
    ("bag", "distro"): "distro",  # the choices, from ros2types when the tree is built
    ("bag", "record", "types_file"): "files yaml",
    ("bag", "snapshot", "topics"): "topic",
    ("bag", "trigger", "topics"): "topic",
}


def _kind(group: str, command: str, param: Any) -> str:
    name = param.name or ""
    for key in ((group, command, name), (group, name), name):
        if key in KINDS:
            if KINDS[key] == "distro":
                from rostools.bag.formats.ros2types import DISTROS

                return "choice:" + ",".join(DISTROS)
            return KINDS[key]
    choices = getattr(param.type, "choices", None)
    if choices:
        return "choice:" + ",".join(str(getattr(c, "value", c)) for c in choices)
    if getattr(param.type, "name", "") == "path":
        return "files"
    return ""


def _first_line(text: str | None) -> str:
    return (text or "").strip().split("\n")[0].replace("``", "'")


def _options(group: str, command: str, params: list[Any]) -> dict[str, Any]:
    options: dict[str, Any] = {}
    for p in params:
        if p.param_type_name != "option" or getattr(p, "hidden", False):
            continue
        value = "" if p.is_flag else (_kind(group, command, p) or "any")
        for name in [*p.opts, *p.secondary_opts]:
            options[name] = {"help": _first_line(p.help), "value": value}
    return options


def _command(group: str, name: str, cmd: Any) -> dict[str, Any]:
    node: dict[str, Any] = {
        "help": _first_line(cmd.help),
        "options": _options(group, name, cmd.params),
    }
    args = [p for p in cmd.params if p.param_type_name == "argument"]
    if args:
        node["args"] = [
            {"name": p.name, "kind": _kind(group, name, p), "many": p.nargs == -1} for p in args
        ]
    return node


def build_tree() -> dict[str, Any]:
    """The command tree of the app, as ``rostools.cli.completer`` reads it."""
    from rostools.cli.app import GROUPS, app as root_app, group_app

    root = typer.main.get_command(root_app)
    tree: dict[str, Any] = {"help": _first_line(root.help), "options": {}, "commands": {}}
    tree["options"] = _options("", "", root.params)
    tree["options"] |= {"-h": {"help": "Show help.", "value": ""}}
    for group, help_text in GROUPS.items():
        cmd = typer.main.get_command(group_app(group))
        subcommands = getattr(cmd, "commands", None)
        if subcommands is None:  # a group of one command (core, demo)
            node = _command(group, group, cmd)
        else:
            node = {"help": help_text, "options": {"-h": {"help": "Show help.", "value": ""}}}
            node["commands"] = {
                name: _command(group, name, sub)
                for name, sub in subcommands.items()
                if not getattr(sub, "hidden", False)
            }
        node["help"] = help_text
        tree["commands"][group] = node
    return tree


def tree_text() -> str:
    """``tree.json``'s content."""
    return json.dumps(build_tree(), indent=1, sort_keys=True) + "\n"


def _plain(value: Any) -> Any:
    return getattr(value, "value", value)  # an enum default as its text


def _quick_param(p: Any) -> dict[str, Any]:
    """How the launcher reads one parameter: its name, and the values it takes."""
    kind = p.type.name
    item: dict[str, Any] = {"dest": p.name, "type": kind, "multiple": bool(p.multiple)}
    if kind == "choice":
        item["choices"] = [str(_plain(c)) for c in p.type.choices]
    if kind in ("float range", "integer range") and (p.type.min, p.type.max) != (None, None):
        item["type"] = "bounded"  # left to Typer
    return item


def quick_specs() -> dict[str, Any]:
    """``quick.json``: the grammar of each command that ``rostools.cli.launch`` may run.

    Written from the Typer app, so both read one command line the same way.
    """
    from rostools.cli.app import GROUPS, app as root_app, group_app

    root = typer.main.get_command(root_app)
    specs: dict[str, Any] = {"": _quick_spec(root, "")}

    for group in GROUPS:
        cmd = typer.main.get_command(group_app(group))
        for name, sub in getattr(cmd, "commands", {}).items():
            target = getattr(sub.callback, "rostools_quick", None)
            if target is not None:
                specs[f"{group} {name}"] = _quick_spec(sub, target)
    return specs


def _quick_spec(cmd: Any, target: str) -> dict[str, Any]:
    options: dict[str, Any] = {}
    args: list[dict[str, Any]] = []
    defaults: dict[str, Any] = {}
    for p in cmd.params:
        defaults[p.name] = _plain(p.default)
        if p.param_type_name == "argument":
            args.append(_quick_param(p) | {"many": p.nargs == -1, "required": p.required})
            continue
        item = _quick_param(p) | {"flag": bool(p.is_flag)}
        if p.is_eager:
            item["type"] = "eager"  # --version: left to Typer
        for name in p.opts:
            options[name] = item
        for name in p.secondary_opts:
            options[name] = item | {"negative": True}
    return {"target": target, "options": options, "args": args, "defaults": defaults}


def quick_text() -> str:
    """``quick.json``'s content."""
    return json.dumps(quick_specs(), indent=1, sort_keys=True) + "\n"


_BASH = r"""# bash completion for rostools (generated by `rostools completion show bash`)
_rostools() {
    local cur=${COMP_WORDS[COMP_CWORD]} IFS=$'\n' line
    local -a out
    out=($(rostools __complete bash "$COMP_CWORD" "${COMP_WORDS[@]}" 2>/dev/null))
    COMPREPLY=()
    case ${out[0]} in
    :files*)
        local exts=${out[0]#:files}
        if [[ -z $exts ]]; then
            COMPREPLY=($(compgen -f -- "$cur"))
        else
            local pat=${exts# }
            COMPREPLY=($(compgen -d -- "$cur") $(compgen -f -X "!*.@(${pat// /|})" -- "$cur"))
        fi
        compopt -o filenames 2>/dev/null
        return;;
    :dirs)
        COMPREPLY=($(compgen -d -- "$cur"))
        compopt -o filenames 2>/dev/null
        return;;
    esac
    for line in "${out[@]}"; do
        COMPREPLY+=("${line%%$'\t'*}")
    done
}
shopt -s extglob 2>/dev/null
complete -o nosort -F _rostools rostools 2>/dev/null || complete -F _rostools rostools
"""

_ZSH = r"""#compdef rostools
# zsh completion for rostools (generated by `rostools completion show zsh`)
_rostools() {
    local -a out values descriptions
    local line
    out=("${(@f)$(rostools __complete zsh $((CURRENT - 1)) "${words[@]}" 2>/dev/null)}")
    case ${out[1]} in
    :files)
        _files; return;;
    :files\ *)
        local exts=${out[1]#:files }
        # _path_files, not _files: _files falls back to every file when none matches
        _path_files -g "*.(${exts// /|})" || _path_files -/; return;;
    :dirs)
        _files -/; return;;
    esac
    for line in $out; do
        [[ -z $line ]] && continue
        values+=("${line%%$'\t'*}")
        if [[ $line == *$'\t'* ]]; then
            descriptions+=("${line%%$'\t'*}  -- ${line#*$'\t'}")
        else
            descriptions+=("${line}")
        fi
    done
    (( ${#values} )) && compadd -Q -l -d descriptions -a values
}
if [[ $zsh_eval_context[-1] == loadautofunc ]]; then
    _rostools "$@"
else
    compdef _rostools rostools
fi
"""

_FISH = r"""# fish completion for rostools (generated by `rostools completion show fish`)
function __rostools_complete
    set -l words (commandline -opc)
    set -l current (commandline -ct)
    set -l out (rostools __complete fish (count $words) $words $current 2>/dev/null)
    switch "$out[1]"
        case ':files'
            __fish_complete_path $current
        case ':files *'
            # __fish_complete_suffix would add every other file too
            set -l exts (string split ' ' (string replace ':files ' '' $out[1]))
            for path in $current*
                if test -d $path
                    echo $path/
                else if contains -- (string split -r -m1 . $path)[-1] $exts
                    echo $path
                end
            end
        case ':dirs'
            __fish_complete_directories $current
        case '*'
            printf '%s\n' $out
    end
end
complete -c rostools -f -a '(__rostools_complete)'
"""

_SCRIPTS = {"bash": _BASH, "zsh": _ZSH, "fish": _FISH}


def script(shell: str) -> str:
    """The completion script for ``shell``."""
    if shell not in _SCRIPTS:
        raise UsageError(f"unknown shell {shell!r} (bash, zsh or fish)")
    return _SCRIPTS[shell]


def write_all() -> list[Path]:
    """Regenerate ``tree.json`` and ``completions/*``; the files written."""
    from rostools.cli.completer import TREE
    from rostools.cli.launch import QUICK

    quick = Path(QUICK)
    TREE.write_text(tree_text())
    quick.write_text(quick_text())
    written = [TREE, quick]
    folder = ROOT / "completions"
    folder.mkdir(exist_ok=True)
    for shell, name in SCRIPT_NAMES.items():
        (folder / name).write_text(script(shell))
        written.append(folder / name)
    return written


ShellArg = Annotated[str, typer.Argument(help="bash, zsh or fish.")]


@app.command()
def show(shell: ShellArg) -> None:
    """Print the completion script (eval it, or save it where your shell looks)."""
    output.put(script(shell))


def install_target(shell: str, home: Path) -> tuple[Path, Path | None, str]:
    """Where ``install`` writes the script, and the rc file line that loads it (if any)."""
    if shell == "bash":
        target = home / ".local/share/bash-completion/completions/rostools"
        return target, home / ".bashrc", f"source {target}"
    if shell == "zsh":
        target = home / ".zfunc" / "_rostools"
        line = "fpath=(~/.zfunc $fpath); autoload -Uz compinit && compinit"
        return target, home / ".zshrc", line
    return home / ".config/fish/completions/rostools.fish", None, ""


@app.command()
def install(ctx: typer.Context, shell: ShellArg, fmt: FormatOpt = None) -> None:
    """Install the script for your user; new shells complete rostools."""
    text = script(shell)
    target, rc, line = install_target(shell, Path.home())
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(text)
    changed = False
    if rc is not None:
        current = rc.read_text() if rc.exists() else ""
        if line not in current:
            with rc.open("a") as f:
                f.write(f"\n# rostools completion\n{line}\n")
            changed = True
    fmt = output_format(ctx, fmt)
    if fmt is Format.text:
        output.put(f"installed {target}\n")
        if changed:
            output.put(f"added to {rc}: {line}\n")
        output.put("open a new shell to use it\n")
    else:
        emit(fmt, {"script": str(target), "rc": str(rc) if changed else None})


if __name__ == "__main__":
    for path in write_all():
        output.line(str(path.relative_to(ROOT)))
