"""The config reference, from the pydantic models: every key with its type, default, allowed
range and description, section by section, a link's keys per link type."""
from __future__ import annotations

import enum
import types
import typing
from collections.abc import Iterator

import annotated_types
from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

_BOUNDS = ((annotated_types.Ge, "ge", ">="), (annotated_types.Gt, "gt", ">"), (annotated_types.Le, "le", "<="),
           (annotated_types.Lt, "lt", "<"), (annotated_types.MinLen, "min_length", "length >="),
           (annotated_types.MaxLen, "max_length", "length <="))


def _models_in(annotation: object) -> list[type[BaseModel]]:
    """The settings models an annotation holds (itself, a list's items, a union's members,
    each registered kind of an annotation whose metadata gives its ``models()``)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    if typing.get_origin(annotation) is typing.Annotated:
        kinds = [m for m in annotation.__metadata__ if callable(getattr(m, "models", None))]
        if kinds:
            return [model for m in kinds for model in m.models()]
    return [m for arg in typing.get_args(annotation) for m in _models_in(arg)]


def type_text(annotation: object) -> str:
    """A key's type as a user reads it: float, int, text, true/false, a list, or one of the
    allowed values."""
    origin = typing.get_origin(annotation)
    if origin is typing.Literal:
        return "one of " + ", ".join(f"`{a}`" for a in typing.get_args(annotation))
    if origin is typing.Annotated:
        return type_text(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return " or ".join(type_text(a) for a in typing.get_args(annotation))
    if origin in (list, tuple, set, frozenset):
        return "list of " + ", ".join(type_text(a) for a in typing.get_args(annotation) if a is not Ellipsis)
    if origin is dict:
        key, value = typing.get_args(annotation)
        return f"table of {type_text(key)} to {type_text(value)}"
    if isinstance(annotation, type) and issubclass(annotation, enum.Enum):
        return "one of " + ", ".join(f"`{m.value}`" for m in annotation)
    names = {float: "number", int: "integer", str: "text", bool: "true/false", type(None): "none"}
    return names.get(annotation, getattr(annotation, "__name__", str(annotation)))


def allowed_text(info: FieldInfo) -> str:
    """The range a key allows, from its constraints."""
    out = []
    for constraint in info.metadata:
        for kind, attr, symbol in _BOUNDS:
            if isinstance(constraint, kind):
                out.append(f"{symbol} {getattr(constraint, attr)}")
        pattern = getattr(constraint, "pattern", None)
        if pattern:
            out.append(f"matching `{pattern}`")
    return ", ".join(out)


def default_text(info: FieldInfo) -> str:
    if info.default_factory is not None:
        try:
            value = info.default_factory()
        except TypeError:
            return "(made)"
        return "(a table)" if isinstance(value, BaseModel) else f"`{value!r}`"
    if info.default is PydanticUndefined:
        return "**required**"
    return "(a table)" if isinstance(info.default, BaseModel) else f"`{info.default!r}`"


def key_rows(model: type[BaseModel], prefix: str = "") -> Iterator[tuple[str, str, str, str, str]]:
    """(key, type, default, allowed, description) of every key of ``model`` that is not a
    table of its own."""
    for name, info in model.model_fields.items():
        if _models_in(info.annotation):
            continue  # a table, with its own section
        description = " ".join((info.description or "").split()).replace("|", "\\|")
        yield (f"{prefix}{name}", type_text(info.annotation).replace("|", "\\|"), default_text(info),
               allowed_text(info).replace("|", "\\|"), description)


def _is_list_of_models(annotation: object) -> bool:
    return typing.get_origin(annotation) is list and bool(_models_in(annotation))


def tables(model: type[BaseModel], prefix: str = "") -> Iterator[tuple[str, type[BaseModel]]]:
    """(dotted name, model) of ``model`` and every table below it, depth first; a list of
    tables by each of its kinds."""
    yield prefix, model
    for name, info in model.model_fields.items():
        kinds = _models_in(info.annotation)
        for sub in kinds:
            tag = "[]" if _is_list_of_models(info.annotation) else ""
            if len(kinds) > 1:  # one of several kinds, told apart by their ``type``
                tag += f" (type = {typing.get_args(sub.model_fields['type'].annotation)[0]!r})"
            yield from tables(sub, f"{prefix}{name}{tag}.")


def config_reference(model: type[BaseModel], title: str) -> str:
    """The Markdown reference of a settings model and the tables it holds."""
    lines = [f"# {title}", "", "Made from the settings' own models when the site is built: "
             "every key, its type, default, allowed range and description.", ""]
    for prefix, sub in tables(model):
        rows = list(key_rows(sub, ""))
        if not rows:
            continue
        lines += [f"## `[{prefix.rstrip('.')}]`" if prefix else "## Top level", ""]
        doc = " ".join((sub.__doc__ or "").strip().split("\n\n")[0].split())
        lines += [doc, ""] if doc else []
        lines += ["| key | type | default | allowed | description |", "|---|---|---|---|---|"]
        lines += [f"| `{k}` | {t} | {d} | {a} | {desc} |" for k, t, d, a, desc in rows]
        lines.append("")
    return "\n".join(lines)
