"""What a ``.xacro`` file may compute while s2r expands it: a checked subset of xacro's expressions.

xacro evaluates every ``${...}`` (and ``$(eval ...)``) with Python's ``eval``; its own filter only refuses
``__`` names at the top level, so a comprehension or an attribute chain reaches arbitrary code. A robot
description from a stranger must not run code, read files outside its package, or copy the environment into
a profile, so while s2r expands a xacro (:func:`sandbox`):

- every expression's syntax tree is checked BEFORE xacro evaluates it (:func:`check_expression`). Allowed:
  number/string/bool/None literals, lists, tuples, dicts and sets of allowed items, arithmetic
  (``+ - * / // % **``), comparisons, ``and or not``, ``a if c else b``, subscripts and slices, names of
  properties, macro parameters and arguments, attribute reads of loaded YAML (``${cfg.camera.fx}``), and
  calls (positional arguments only) of: the ``math`` functions xacro exposes (``radians``, ``sqrt``,
  ``math.atan2``, ...), ``abs len min max round sum int float str bool list tuple dict range sorted``
  (also as ``python.*``), and ``xacro.load_yaml / xacro.arg / xacro.abs_filename / xacro.dotify /
  xacro.tokenize / xacro.fatal``. Refused: any name or attribute starting with ``_`` (at any depth), other
  calls (methods, ``type``, ``vars``, ``map``...), keyword arguments, ``str.format``, comprehensions,
  generators, lambdas, ``:=``, ``*args``. In ``$(eval ...)`` Python's builtins are visible, so there every
  builtin name but the allowed calls is refused as well;
- names are checked, and so are the objects behind them: when an expression is evaluated, every function it
  calls must BE one of the allowed functions (:func:`check_callees`, by identity), so a property or macro parameter
  named ``len`` bound to ``'-'.join`` or ``map`` is refused; and no expression may evaluate to a function or class,
  so a property can never hold something to call;
- ``xacro.load_yaml`` and ``<xacro:include>`` read only files under the description's folder (or its ROS
  package, the nearest folder above holding a ``package.xml``) and the package folders (``--package-path``,
  ``ROS_PACKAGE_PATH``);
- a file (the description or an include) holding ``<!DOCTYPE`` is refused: no entity expansion;
- ``$(env NAME)`` and ``$(optenv NAME default)`` never read the machine's environment. They see only the values
  passed explicitly (``--env NAME=VALUE``: Clearpath robots switch accessories on with ``JACKAL_BB2=1``):
  ``env`` of a name not passed is refused, ``optenv`` of one takes its default. A profile thus depends on the
  files and the values given, not on the machine's environment, and no other environment value reaches an output.
"""

from __future__ import annotations

import ast
import builtins
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

__all__ = ["UnsafeXacro", "allowed_functions", "check_callees", "check_expression", "check_no_doctype", "sandbox"]

_MATH = frozenset(k for k in vars(math) if not k.startswith("_"))
_PLAIN_CALLS = frozenset({"abs", "len", "min", "max", "round", "sum", "int", "float", "str", "bool", "list",
                          "tuple", "dict", "range", "sorted"})
_XACRO_CALLS = frozenset({"load_yaml", "arg", "abs_filename", "dotify", "tokenize", "fatal"})
#: Namespaces that may be read or called only through the listed attributes.
_NAMESPACES: dict[str, frozenset[str]] = {
    "math": _MATH,
    "python": _PLAIN_CALLS | {"True", "False"},
    "xacro": _XACRO_CALLS,
}
#: Names callable directly (xacro's globals, and ``$(eval)``'s ``arg``/``find``/``dirname``).
_CALLS = _MATH | _PLAIN_CALLS | {"load_yaml", "abs_filename", "dotify", "arg", "find", "dirname", "optenv", "env"}
#: Attributes that reach code or object internals from plain data (``"{0.__class__}".format(x)``).
_BAD_ATTRS = frozenset({"format", "format_map", "mro"})
_BAD_ATTR_PREFIXES = ("_", "gi_", "f_", "co_", "tb_", "cr_", "ag_")
_SAFE_BUILTIN_NAMES = _PLAIN_CALLS | {"True", "False", "None"}
_ALLOWED_NODES: tuple[type[ast.AST], ...] = (
    ast.Expression, ast.Constant, ast.Name, ast.Load, ast.List, ast.Tuple, ast.Set, ast.Dict,
    ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.Compare, ast.IfExp, ast.Subscript, ast.Slice, ast.Attribute, ast.Call,
    ast.JoinedStr, ast.FormattedValue, ast.operator, ast.unaryop, ast.boolop, ast.cmpop,
)
_MAX_EXPRESSION_CHARS = 10_000


class UnsafeXacro(ValueError):
    """A xacro expression, file access or environment lookup that s2r refuses (the message says which)."""


def _describe(node: ast.AST) -> str:
    names = {ast.ListComp: "a list comprehension", ast.SetComp: "a set comprehension",
             ast.DictComp: "a dict comprehension", ast.GeneratorExp: "a generator expression",
             ast.Lambda: "a lambda", ast.NamedExpr: "an assignment expression (:=)", ast.Starred: "*unpacking"}
    return names.get(type(node), type(node).__name__)


def _check_name(name: str, *, builtins_visible: bool) -> None:
    if name.startswith("_"):
        raise UnsafeXacro(f"name {name!r} is refused (names starting with '_' reach Python internals)")
    if name in _NAMESPACES:
        raise UnsafeXacro(f"{name!r} may be used only as {name}.<function>")
    if builtins_visible and hasattr(builtins, name) and name not in _SAFE_BUILTIN_NAMES:
        raise UnsafeXacro(f"Python builtin {name!r} is refused in $(eval ...)")


def _check_attribute(node: ast.Attribute) -> None:
    attr = node.attr
    if attr.startswith(_BAD_ATTR_PREFIXES) or attr in _BAD_ATTRS:
        raise UnsafeXacro(f"attribute {attr!r} is refused (it reaches Python internals)")
    if isinstance(node.value, ast.Name) and node.value.id in _NAMESPACES and attr not in _NAMESPACES[node.value.id]:
        raise UnsafeXacro(f"{node.value.id}.{attr} is not among the functions s2r allows in xacro expressions")


def _check_call(node: ast.Call) -> None:
    func = node.func
    if node.keywords:
        raise UnsafeXacro("keyword arguments are refused in xacro expressions")
    if isinstance(func, ast.Name) and func.id in _CALLS:
        return
    if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name) and func.value.id in _NAMESPACES:
        return  # the attribute itself is checked against the namespace's list
    raise UnsafeXacro(f"calling {ast.unparse(func)[:60]!r} is refused (only math functions and xacro's helpers)")


def check_expression(text: str, *, builtins_visible: bool = False) -> None:
    """Raise :class:`UnsafeXacro` unless ``text`` is an expression of the allowed subset (module docstring).

    ``builtins_visible`` is for ``$(eval ...)``, where Python's builtins are reachable by name.
    """
    if len(text) > _MAX_EXPRESSION_CHARS:
        raise UnsafeXacro(f"expression longer than {_MAX_EXPRESSION_CHARS} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise UnsafeXacro(f"invalid expression syntax ({exc.msg})") from None
    except (RecursionError, MemoryError, ValueError):
        raise UnsafeXacro("expression too deeply nested or malformed") from None
    bases = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name)}
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED_NODES):
            raise UnsafeXacro(f"{_describe(node)} is refused in xacro expressions")
        if isinstance(node, ast.Name):
            if node.id in _NAMESPACES and id(node) in bases:
                continue  # math.<f>, python.<f>, xacro.<f>: the attribute is checked against the namespace
            _check_name(node.id, builtins_visible=builtins_visible)
        elif isinstance(node, ast.Attribute):
            _check_attribute(node)
        elif isinstance(node, ast.Call):
            _check_call(node)


def allowed_functions(symbols: Mapping[str, Any]) -> list[Any]:
    """The function objects an expression may call: xacro's global ``symbols`` bound to the allowed call names
    (directly and in the ``math`` / ``python`` / ``xacro`` namespaces) and the allowed Python builtins."""
    found: list[Any] = [getattr(builtins, name) for name in _PLAIN_CALLS]
    found += [v for name in _CALLS if callable(v := symbols.get(name))]
    for space, names in _NAMESPACES.items():
        table = symbols.get(space)
        if isinstance(table, Mapping):
            found += [v for name in names if callable(v := table.get(name))]
    return found


def _callee(node: ast.expr, symbols: Mapping[str, Any]) -> tuple[bool, Any]:
    """(found, object) a call's function name refers to in ``symbols`` (a xacro symbol table); (False, None)
    when the name is unbound (eval then reports the NameError itself)."""
    try:
        if isinstance(node, ast.Name):
            return True, symbols[node.id]
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            return True, symbols[node.value.id][node.attr]
    except (KeyError, TypeError, AttributeError):
        return False, None
    return False, None


def check_callees(text: str, symbols: Mapping[str, Any], allowed: Sequence[Any]) -> None:
    """Raise :class:`UnsafeXacro` unless every function ``text`` calls IS one of ``allowed`` (by identity): a
    property or macro parameter named ``len`` bound to ``'-'.join`` or ``map`` is not the builtin ``len``."""
    tree = ast.parse(text.strip(), mode="eval")
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        found, obj = _callee(node.func, symbols)
        if found and not any(obj is fn for fn in allowed):
            name = ast.unparse(node.func)[:60]
            raise UnsafeXacro(f"calling {name!r} is refused: that name is bound to a {type(obj).__name__}, not the "
                              "allowed function (a property or parameter shadows it)")


def _not_callable(value: Any, expr: Any) -> Any:
    """``value``, unless it is a function or class: a property must hold data, never something to call."""
    if callable(value):
        shown = str(expr).strip()[:60]
        raise UnsafeXacro(f"expression {shown!r} evaluates to a function ({type(value).__name__}): a property or "
                          "argument must hold a value, not a function")
    return value


def _inside(path: Path, roots: Sequence[Path]) -> bool:
    return any(path == root or root in path.parents for root in roots)


def allowed_roots(description: Path, package_paths: Sequence[Path]) -> list[Path]:
    """Folders a description may read from: its folder, its ROS package (``package.xml`` up to 3 levels
    above), and the package search folders; resolved (symlinks followed)."""
    folder = description.resolve().parent
    roots = [folder]
    for parent in [folder, *list(folder.parents)[:3]]:
        if (parent / "package.xml").is_file():
            roots.append(parent)
            break
    return roots + [Path(p).resolve() for p in package_paths]


def _checked_file(filename: str, roots: Sequence[Path], what: str) -> str:
    resolved = Path(filename).resolve()
    if not _inside(resolved, roots):
        raise UnsafeXacro(f"{what} {filename!r} is outside the description's folder and the package folders "
                          "(pass --package-path to allow another folder)")
    return filename


def check_no_doctype(filename: str | Path) -> None:
    """Refuse a xacro file that declares a DOCTYPE (entities: "billion laughs" amplification, external files)."""
    try:
        head = Path(filename).read_bytes()
    except OSError:
        return  # xacro reports the missing or unreadable file itself
    if b"<!DOCTYPE" in head or b"<!ENTITY" in head:
        raise UnsafeXacro(f"{Path(filename).name}: XML with a <!DOCTYPE> (DTD or entity declarations) is refused "
                          "(remove the <!DOCTYPE ...> block)")


@contextmanager
def _patched(obj: Any, name: str, value: Any) -> Iterator[None]:
    saved = obj[name] if isinstance(obj, dict) else getattr(obj, name)
    if isinstance(obj, dict):
        dict.__setitem__(obj, name, value)
    else:
        setattr(obj, name, value)
    try:
        yield
    finally:
        if isinstance(obj, dict):
            dict.__setitem__(obj, name, saved)
        else:
            setattr(obj, name, saved)


def _env_lookups(env: Mapping[str, str]) -> tuple[Callable[[str], str], Callable[..., str]]:
    """``$(env NAME)`` and ``$(optenv NAME default)`` answered from ``env`` (the ``--env`` values) only."""

    def env_value(name: str) -> str:
        if name in env:
            return env[name]
        raise UnsafeXacro(f"$(env {name}) is refused: s2r does not read the environment while expanding xacro, "
                          f"only --env values (pass --env {name}=VALUE)")

    def optenv_value(name: str, default: str = "") -> str:
        return env.get(name, default)

    return env_value, optenv_value


@contextmanager
def sandbox(description: Path, package_paths: Sequence[Path], *, env: Mapping[str, str] | None = None,
            included: list[str] | None = None) -> Iterator[None]:
    """Expand xacro within this block under the rules of the module docstring (patches the ``xacro`` module).

    ``env``: the values ``$(env NAME)`` / ``$(optenv NAME default)`` see (``--env NAME=VALUE``); nothing else.
    ``included``: when given, the path of every file ``<xacro:include>`` reads is appended to it.
    """
    env_value, optenv_value = _env_lookups(dict(env or {}))
    import xacro
    from xacro import substitution_args as subst

    roots = allowed_roots(description, package_paths)
    check_no_doctype(description)
    safe_eval: Callable[..., Any] = xacro.safe_eval
    subst_eval: Callable[..., Any] = subst._eval
    load_yaml: Callable[..., Any] = xacro.load_yaml
    include_files: Callable[..., Any] = xacro.get_include_files

    allowed: list[Any] = []  # the allowed functions themselves, filled once the patches below are in place

    def checked_eval(expr: Any, symbols: Any, *args: Any, **kwargs: Any) -> Any:
        if isinstance(expr, str):
            check_expression(expr)
            check_callees(expr, symbols, allowed)
        return _not_callable(safe_eval(expr, symbols, *args, **kwargs), expr)

    def checked_subst_eval(expr: str, context: Any) -> Any:
        check_expression(expr, builtins_visible=True)
        return _not_callable(subst_eval(expr, context), expr)

    def checked_load_yaml(filename: Any) -> Any:
        return load_yaml(_checked_file(xacro.abs_filename_spec(str(filename)), roots, "load_yaml of"))

    def checked_includes(spec: Any, symbols: Any) -> Iterator[str]:
        for name in include_files(spec, symbols):
            check_no_doctype(_checked_file(name, roots, "include of"))
            if included is not None:
                included.append(name)
            yield name

    symbols = xacro._global_symbols
    with ExitStack() as stack:
        for obj, name, value in (
            (xacro, "safe_eval", checked_eval), (subst, "_eval", checked_subst_eval),
            (xacro, "get_include_files", checked_includes),
            (symbols, "load_yaml", checked_load_yaml), (symbols["xacro"], "load_yaml", checked_load_yaml),
            (subst, "_eval_env", env_value), (subst, "_eval_optenv", optenv_value),
            (subst._eval_dict, "env", env_value), (subst._eval_dict, "optenv", optenv_value),
        ):
            stack.enter_context(_patched(obj, name, value))
        allowed.extend(allowed_functions(symbols))
        yield
