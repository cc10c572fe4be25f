"""Paste the kernel's inline stages into their caller at the source level, before numba compiles it.

numba's own ``inline="always"`` pastes a callee's *IR*: at every call site it runs the untyped
pipeline over the callee again and deep-copies the result twice, and a stage that itself pastes
helpers is copied at each level. On the kernel's halves that was the largest single cost of a
first compile (about a third of it, measured with numba 0.68). :func:`flatten` does the same
pasting on the Python syntax tree instead, once, so numba compiles one plain function:

* a call to an :func:`analytic.kernel.jit.inline` function (a global name, or a module's
  attribute: ``gauss.join(...)``) that stands as a statement
  (``stage(...)``), as the whole right-hand side of an assignment (``a, b = helper(...)``), as an
  ``if`` test (``if not helper(...)``) or as a returned value is
  replaced by the callee's body, its locals renamed apart, its parameters bound to the arguments
  (a plain name or constant argument is substituted where the callee never rebinds the parameter),
  and its final ``return value`` turned into the assignment;
* a callee with early returns is pasted as one ``while True: ... break`` block whose returns
  assign the result and break out (a return inside a loop also sets a flag that breaks the loops
  around it);
* a callee is pasted only when it uses nothing but plain statements and expressions (no nested
  functions, lambdas, comprehensions, ``global``, ``yield``, ``try``) and closes over numbers
  only (a factory's constants, pasted as literals); any other inline call is left to numba's
  own inlining, which gives the same code;
* the names of the callees' module-level numbers (the :mod:`analytic.kernel.layout` offsets, for
  example) become literal constants and constant sub-expressions are folded, as numba would have
  frozen them anyway: fewer statements to type and lower.

The result computes exactly what the original computes (same operations in the same order); a
test compiles both and compares every output bit for bit. Without numba, or for a function numba
would not compile anyway, nothing is rewritten.
"""

from __future__ import annotations

import ast
import builtins
import dataclasses
import functools
import itertools
import linecache
import operator
import textwrap
import types
from collections.abc import Callable
from typing import Any

_FOLD = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
    ast.BitAnd: operator.and_,
    ast.BitOr: operator.or_,
}
"""Operators folded when both operands are int constants (exact in Python and in int64)."""

_NOT_PASTEABLE = (
    ast.FunctionDef,
    ast.AsyncFunctionDef,
    ast.Lambda,
    ast.ListComp,
    ast.SetComp,
    ast.DictComp,
    ast.GeneratorExp,
    ast.Global,
    ast.Nonlocal,
    ast.Yield,
    ast.YieldFrom,
    ast.Await,
    ast.Try,
    ast.With,
)


def is_inline(obj: Any) -> bool:
    """True for a numba dispatcher compiled with ``inline="always"`` (a kernel stage or helper)."""
    opts = getattr(obj, "targetoptions", None)
    return isinstance(opts, dict) and opts.get("inline") == "always" and hasattr(obj, "py_func")


class NoSource(LookupError):
    """A function's source is not available (an install without ``.py`` files, or a file changed
    since import): it is not pasted, and numba inlines it as before (same numbers)."""


def _function_def(fn: Callable) -> ast.FunctionDef:
    """A fresh syntax tree of ``fn``'s definition, with the line numbers of its file (its lines
    are those its code object spans; the file is read through :mod:`linecache`)."""
    code = fn.__code__
    last = max(end or 0 for _, end, _, _ in code.co_positions())
    lines = linecache.getlines(code.co_filename)[code.co_firstlineno - 1 : last]
    try:
        tree = ast.parse("\n" * (code.co_firstlineno - 1) + textwrap.dedent("".join(lines)))
    except SyntaxError as exc:  # the file changed since it was imported
        raise NoSource(fn.__qualname__) from exc
    fdef = tree.body[0] if tree.body else None
    if not isinstance(fdef, ast.FunctionDef) or fdef.name != code.co_name:
        raise NoSource(fn.__qualname__)  # no source installed, or not this function's
    fdef.decorator_list = []
    return fdef


def _body(fdef: ast.FunctionDef) -> list[ast.stmt]:
    """The statements of ``fdef`` without its docstring."""
    body = fdef.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        body = body[1:]
    return list(body)


@dataclasses.dataclass(frozen=True)
class _Shape:
    """What pasting needs to know of a callee (computed once per function)."""

    params: tuple[str, ...]
    stored: frozenset[str]  # names its body binds
    pasteable: bool  # positional parameters only, plain statements
    early_return: bool  # a ``return`` other than the last statement


@functools.cache
def _shape(fn: Callable) -> _Shape:
    """The shape of a callee (its source parsed once per process)."""
    return _shape_of(_function_def(fn), fn)


def _shape_of(fdef: ast.FunctionDef, fn: Callable) -> _Shape:
    a = fdef.args
    body = _body(fdef)
    stored, plain, returns = set(), True, []
    for stmt in body:
        for n in ast.walk(stmt):
            if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store):
                stored.add(n.id)
            elif isinstance(n, ast.Return):
                returns.append(n)
            elif isinstance(n, _NOT_PASTEABLE):
                plain = False
    simple_args = not (a.vararg or a.kwarg or a.kwonlyargs or a.defaults or a.posonlyargs)
    final = bool(body) and isinstance(body[-1], ast.Return)
    return _Shape(
        params=tuple(x.arg for x in a.args),
        stored=frozenset(stored),
        pasteable=plain and simple_args and _closure_numbers(fn) is not None,
        early_return=len(returns) > (1 if final else 0),
    )


def _closure_numbers(fn: Callable) -> dict[str, Any] | None:
    """The values of ``fn``'s closure variables by name when every one is a number (a factory's
    constants: pasted as literals, like module numbers), else None (not pasted)."""
    cells = fn.__closure__ or ()
    values = dict(zip(fn.__code__.co_freevars, (c.cell_contents for c in cells), strict=True))
    return values if all(_is_number(v) for v in values.values()) else None


def _has_return(nodes: list[ast.stmt]) -> bool:
    return any(isinstance(n, ast.Return) for stmt in nodes for n in ast.walk(stmt))


def _single_exit(
    body: list[ast.stmt], ret: str | None, done: str, site: ast.stmt
) -> list[ast.stmt]:
    """``body`` of a function with early returns as one block that falls through: wrapped in
    ``while True: ... break``, each ``return v`` becomes ``ret = v; break`` (inside a loop also
    ``done = True``, and every loop that holds one is followed by ``if done: break``)."""

    def name(ident: str, ctx: ast.expr_context, where: ast.AST) -> ast.Name:
        return _at(ast.Name(ident, ctx), where)

    def block(stmts: list[ast.stmt], in_loop: bool) -> list[ast.stmt]:
        out: list[ast.stmt] = []
        for stmt in stmts:
            if isinstance(stmt, ast.Return):
                if ret is not None and stmt.value is not None:
                    out.append(_at(ast.Assign([name(ret, ast.Store(), stmt)], stmt.value), stmt))
                if in_loop:
                    true = _at(ast.Constant(True), stmt)
                    out.append(_at(ast.Assign([name(done, ast.Store(), stmt)], true), stmt))
                out.append(_at(ast.Break(), stmt))
                break  # what follows a return never runs
            if isinstance(stmt, ast.For | ast.While) and _has_return(stmt.body):
                stmt.body = block(stmt.body, True)
                out.append(stmt)
                test = name(done, ast.Load(), stmt)
                out.append(_at(ast.If(test, [_at(ast.Break(), stmt)], []), stmt))
                continue
            if isinstance(stmt, ast.If) and _has_return([stmt]):
                stmt.body = block(stmt.body, in_loop)
                stmt.orelse = block(stmt.orelse, in_loop)
            out.append(stmt)
        return out

    inner = block(body, False)
    if not inner or not isinstance(inner[-1], ast.Break):
        inner.append(_at(ast.Break(), site))
    false = _at(ast.Constant(False), site)
    head = _at(ast.Assign([name(done, ast.Store(), site)], false), site)
    return [head, _at(ast.While(_at(ast.Constant(True), site), inner, []), site)]


def _at(node: ast.AST, where: ast.AST) -> ast.AST:
    return ast.copy_location(node, where)


def _is_number(value: Any) -> bool:
    return type(value) in (int, float)


class _Rewrite(ast.NodeTransformer):
    """Rename a callee's locals, substitute its parameters, resolve its global names (numbers
    become constants) and fold constant integer sub-expressions."""

    def __init__(self, rename: dict[str, str], subst: dict[str, ast.expr], resolve) -> None:
        self.rename = rename
        self.subst = subst
        self.resolve = resolve

    def visit_Name(self, node: ast.Name) -> ast.expr:
        if node.id in self.subst and isinstance(node.ctx, ast.Load):
            return ast.copy_location(_copy(self.subst[node.id]), node)
        if node.id in self.rename:
            return ast.copy_location(ast.Name(self.rename[node.id], node.ctx), node)
        if isinstance(node.ctx, ast.Load):
            return ast.copy_location(self.resolve(node.id), node)
        return node

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        op = _FOLD.get(type(node.op))
        left, right = node.left, node.right
        if (
            op is not None
            and isinstance(left, ast.Constant)
            and isinstance(right, ast.Constant)
            and type(left.value) is int
            and type(right.value) is int
            and not (isinstance(node.op, ast.FloorDiv | ast.Mod) and right.value == 0)
        ):
            return ast.copy_location(ast.Constant(op(left.value, right.value)), node)
        return node


def _copy(node: ast.expr) -> ast.expr:
    """A fresh node for a substituted argument (a name or a constant)."""
    if isinstance(node, ast.Name):
        return ast.Name(node.id, ast.Load())
    return ast.Constant(node.value)


class _Paster:
    """Pastes inline calls into one function; collects the globals the result needs."""

    def __init__(self, globals_: dict[str, Any]) -> None:
        self.globals = dict(globals_)
        self.sites = itertools.count()
        self.pasted = 0

    def alias(self, name: str, value: Any, prefix: str) -> str:
        """A global name under which ``value`` is visible to the pasted code."""
        if self.globals.get(name, value) is value:
            self.globals[name] = value
            return name
        self.globals[prefix + name] = value
        return prefix + name

    def callee(self, func: ast.expr) -> Any:
        """What a call's ``func`` names: a global (``stage(...)``) or a function of a module
        the code imported (``gauss.join(...)``); None for anything else."""
        if isinstance(func, ast.Name):
            return self.globals.get(func.id)
        if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
            module = self.globals.get(func.value.id)
            if isinstance(module, types.ModuleType):
                return getattr(module, func.attr, None)
        return None

    def expand(self, stmts: list[ast.stmt]) -> list[ast.stmt]:
        out: list[ast.stmt] = []
        for stmt in stmts:
            out.extend(self.expand_stmt(stmt))
        return out

    def hoist(self, stmt: ast.stmt) -> list[ast.stmt]:
        """``if [not] f(...)`` and ``return f(...)`` with f inline: the call first, as an
        assignment to a fresh name that the test or the return then reads."""
        holder, field = stmt, "test" if isinstance(stmt, ast.If) else "value"
        expr = getattr(stmt, field, None) if isinstance(stmt, ast.If | ast.Return) else None
        if isinstance(expr, ast.UnaryOp) and isinstance(expr.op, ast.Not):
            holder, field, expr = expr, "operand", expr.operand
        if not (isinstance(expr, ast.Call) and is_inline(self.callee(expr.func))):
            return [stmt]
        name = f"_value{next(self.sites)}"
        setattr(holder, field, _at(ast.Name(name, ast.Load()), expr))
        target = _at(ast.Name(name, ast.Store()), stmt)
        return [_at(ast.Assign([target], expr), stmt), stmt]

    def expand_stmt(self, stmt: ast.stmt) -> list[ast.stmt]:
        hoisted = self.hoist(stmt)
        if len(hoisted) > 1:
            return self.expand(hoisted)
        call, target = None, None
        if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Call):
            call = stmt.value
        elif (
            isinstance(stmt, ast.Assign)
            and len(stmt.targets) == 1
            and isinstance(stmt.value, ast.Call)
        ):
            call, target = stmt.value, stmt.targets[0]
        if call is not None and not call.keywords:
            obj = self.callee(call.func)
            if is_inline(obj) and not any(isinstance(a, ast.Starred) for a in call.args):
                pasted = self.paste(obj.py_func, call.args, target, stmt)
                if pasted is not None:
                    return pasted
        for field in ("body", "orelse"):
            block = getattr(stmt, field, None)
            if isinstance(block, list) and block and isinstance(block[0], ast.stmt):
                setattr(stmt, field, self.expand(block))
        return [stmt]

    def resolver(self, fn: Callable, prefix: str):
        """How a global name of ``fn`` reads in the pasted code: a number as a constant, anything
        else as a name (aliased when the caller's globals bind the same name otherwise)."""
        fglobals = fn.__globals__
        closure = _closure_numbers(fn) or {}

        def resolve(name: str) -> ast.expr:
            if name in closure:  # a callee's closure constant (the caller keeps its own cells)
                return ast.Constant(closure[name])
            if name not in fglobals:
                if not hasattr(builtins, name):
                    raise NameError(f"{fn.__qualname__}: {name} is not defined")
                return ast.Name(name, ast.Load())
            value = fglobals[name]
            if _is_number(value):
                return ast.Constant(value)
            return ast.Name(self.alias(name, value, prefix), ast.Load())

        return resolve

    def paste(self, fn: Callable, args: list[ast.expr], target, site: ast.stmt):
        """The statements that replace ``site`` (a call of ``fn``), or None to leave it."""
        try:
            shape = _shape(fn)
        except NoSource:
            return None
        if not shape.pasteable or len(shape.params) != len(args):
            return None
        body = _body(_function_def(fn))
        prefix = f"_{fn.__name__}{next(self.sites)}_"
        rename = {name: prefix + name for name in shape.stored | set(shape.params)}
        subst: dict[str, ast.expr] = {}
        binds: list[ast.stmt] = []
        for p, a in zip(shape.params, args, strict=True):
            if p not in shape.stored and isinstance(a, ast.Name | ast.Constant):
                subst[p] = a
                del rename[p]
            else:
                binds.append(
                    _at(ast.Assign([_at(ast.Name(rename[p], ast.Store()), site)], a), site)
                )
        rewrite = _Rewrite(rename, subst, self.resolver(fn, prefix))
        body = [rewrite.visit(stmt) for stmt in body]
        final = body.pop() if body and isinstance(body[-1], ast.Return) else None
        if shape.early_return:  # one block with a single exit
            if final is not None:
                body.append(final)
            ret = prefix + "return" if target is not None else None
            body = _single_exit(body, ret, prefix + "done", site)
            if ret is not None:
                body.append(_at(ast.Assign([target], _at(ast.Name(ret, ast.Load()), site)), site))
        elif target is not None:
            value = final.value if final is not None else None
            body.append(_at(ast.Assign([target], value or _at(ast.Constant(None), site)), site))
        self.pasted += 1
        return self.expand(binds + body) or [_at(ast.Pass(), site)]


def flatten(fn: Callable) -> Callable:
    """``fn`` with every pasteable inline call in its body replaced by the callee's code (module
    docstring), as a new function of the same name, closure values and source file (numba's cache
    keys on the file). Returns ``fn`` itself when there is nothing to paste, or when its source
    is not available (:class:`NoSource`).

    The pasted code depends only on ``fn``'s code and globals, not on its closure values (they
    stay closure variables), so the variants a factory makes (one per solve) are pasted once per
    process and each gets its own closure."""
    key = (fn.__code__, id(fn.__globals__))
    if key not in _factories:
        _factories[key] = _pasted_factory(fn)
    factory = _factories[key]
    if factory is None:
        return fn
    cells = [c.cell_contents for c in fn.__closure__ or ()]
    new = factory(*cells)
    new.__qualname__ = fn.__qualname__
    new.__module__ = fn.__module__
    new.__doc__ = fn.__doc__
    return new


_factories: dict[tuple[Any, int], Callable | None] = {}
""":func:`flatten`'s pasted code by the original's code object (and globals)."""


def _pasted_factory(fn: Callable) -> Callable | None:
    """A function of ``fn``'s closure values that returns the pasted function, or None when
    nothing is pasted (or the source is not available)."""
    try:
        fdef = _function_def(fn)
    except NoSource:
        return None
    shape = _shape_of(fdef, fn)  # not cached: a factory makes a new function each time
    paster = _Paster(fn.__globals__)
    local = shape.stored | set(shape.params) | set(fn.__code__.co_freevars)
    own = paster.resolver(fn, "")

    def resolve(name: str) -> ast.expr:
        return ast.Name(name, ast.Load()) if name in local else own(name)

    fdef = _Rewrite({}, {}, resolve).visit(fdef)  # its own numbers to constants
    fdef.body = paster.expand(fdef.body)
    if paster.pasted == 0:
        return None
    free = fn.__code__.co_freevars
    where = {"lineno": fdef.lineno, "col_offset": 0, "end_lineno": fdef.lineno, "end_col_offset": 0}
    factory = ast.FunctionDef(
        name="_pasted_factory",
        args=ast.arguments(
            posonlyargs=[],
            args=[ast.arg(name, **where) for name in free],
            kwonlyargs=[],
            kw_defaults=[],
            defaults=[],
        ),
        body=[fdef, ast.Return(ast.Name(fdef.name, ast.Load(), **where), **where)],
        decorator_list=[],
        **where,
    )
    module = ast.Module([factory], type_ignores=[])  # every node pasted or made has a location
    namespace = paster.globals
    exec(compile(module, fn.__code__.co_filename, "exec"), namespace)
    return namespace.pop("_pasted_factory")


__all__ = ["NoSource", "flatten", "is_inline"]
