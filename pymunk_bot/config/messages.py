"""Turning pydantic's errors into one-line messages with a key path and a did-you-mean."""
from __future__ import annotations

import difflib
import types
import typing
from typing import Any

from pydantic import BaseModel


def _unwrap(tp: Any) -> Any:
    """Strip Annotated and Optional (X | None) wrappers."""
    while True:
        origin = typing.get_origin(tp)
        if origin is typing.Annotated:
            tp = typing.get_args(tp)[0]
        elif origin in (typing.Union, types.UnionType):
            args = [a for a in typing.get_args(tp) if a is not type(None)]
            if len(args) != 1:
                return tp
            tp = args[0]
        else:
            return tp


_DISCRIMINATORS = ("type", "drive")  # the keys that pick a section's model


def _tagged_members(tp: Any) -> dict[str, type[BaseModel]] | None:
    """For a discriminated union of models on ``type``: tag -> model."""
    if typing.get_origin(tp) not in (typing.Union, types.UnionType):
        return None
    members = {}
    for arg in typing.get_args(tp):
        arg = _unwrap(arg)
        if isinstance(arg, type) and issubclass(arg, BaseModel):
            for key in _DISCRIMINATORS:
                if key in arg.model_fields:
                    for tag in typing.get_args(arg.model_fields[key].annotation):
                        members[tag] = arg
                    break
    return members or None


def walk(model: type[BaseModel], loc: tuple) -> tuple[str, tuple, type[BaseModel] | None]:
    """Follow a pydantic error location through the models.

    Returns the user-facing key path ("robots[0].lidar.beams"), the location with union tags
    removed (for line look-ups), and the model that owns the last key (for did-you-mean).
    """
    path, clean = "", []
    tp: Any = model
    owner: type[BaseModel] | None = model
    parts = list(loc)
    while parts:
        part = parts.pop(0)
        tp = _unwrap(tp)
        members = _tagged_members(tp)
        if members is not None and isinstance(part, str) and part in members:
            tp = owner = members[part]
            continue
        if isinstance(part, int):
            path += f"[{part}]"
            clean.append(part)
            args = typing.get_args(tp)
            tp = args[0] if args and typing.get_origin(tp) in (list, tuple) else Any
            continue
        path += f".{part}" if path else str(part)
        clean.append(part)
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            owner = tp
            field = tp.model_fields.get(part)
            tp = field.annotation if field is not None else Any
        elif typing.get_origin(tp) is dict:
            tp = typing.get_args(tp)[1]
        else:
            tp = Any
        tp_model = _unwrap(tp)
        if not (isinstance(tp_model, type) and issubclass(tp_model, BaseModel)) and parts:
            owner = None
    return path, tuple(clean), owner


# A misspelt key shows up as an unknown key *and* a missing one: report the unknown key first.
_PRIORITY = {"extra_forbidden": 0, "union_tag_invalid": 1}


def most_helpful(errors: list[dict]) -> dict:
    """The error to show when pydantic found several."""
    return min(errors, key=lambda e: _PRIORITY.get(e["type"], 2))


def did_you_mean(word: str, choices: typing.Iterable[str]) -> str:
    match = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean '{match[0]}'?)" if match else ""


MAX_ECHO = 80  # [characters] of a user's value quoted back in a message


def clip(text: str, limit: int = MAX_ECHO) -> str:
    """``text`` cut to ``limit`` characters, saying how long it was: a message quoting a user's
    value stays one readable line however long the value."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text):,} characters)"


def _shown(value: Any) -> str:
    if isinstance(value, str):
        return clip(repr(value))
    if isinstance(value, (dict, list)) and len(repr(value)) > 40:
        return type(value).__name__
    return clip(repr(value)) if not isinstance(value, float) else f"{value:g}"


def describe(error: dict, owner: type[BaseModel] | None) -> str:
    """One problem, worded for a person editing YAML."""
    kind, ctx, value = error["type"], error.get("ctx") or {}, error.get("input")
    got = f" (got {_shown(value)})"
    if kind == "extra_forbidden":
        key = str(error["loc"][-1])
        known = owner.model_fields if owner is not None else {}
        return f"unknown key{did_you_mean(key, known)}; valid keys: {', '.join(known)}"
    if kind == "missing":
        last = error["loc"][-1] if error["loc"] else None
        if isinstance(last, int):  # a fixed-length list (tuple) that is too short
            return f"must have {last + 1} items (got {last})"
        return "required key is missing"
    if kind == "union_tag_invalid":
        tags = [t.strip().strip("'") for t in str(ctx.get("expected_tags", "")).split(",")]
        tag = str(ctx.get("tag"))
        return f"unknown type '{tag}'{did_you_mean(tag, tags)}; expected one of: {', '.join(tags)}"
    if kind == "union_tag_not_found":
        return "required key 'type' is missing"
    bounds = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<",
              "less_than_equal": "<="}
    if kind in bounds:
        bound = next(iter(ctx.values()))
        return f"must be {bounds[kind]} {bound:g}{got}"
    if kind in ("float_type", "float_parsing"):
        return f"must be a number{got}"
    if kind in ("int_type", "int_parsing", "int_from_float"):
        return f"must be an integer{got}"
    if kind in ("bool_type", "bool_parsing"):
        return f"must be true or false{got}"
    if kind in ("string_type",):
        return f"must be a string{got}"
    if kind == "finite_number":
        return f"must be a finite number{got}"
    if kind == "string_pattern_mismatch":
        return f"must match {ctx.get('pattern', '').strip('^$')}{got}"
    if kind == "too_short":
        return f"must have at least {ctx.get('min_length')} items (got {ctx.get('actual_length')})"
    if kind == "too_long":
        return f"must have at most {ctx.get('max_length')} items (got {ctx.get('actual_length')})"
    if kind in ("tuple_type", "list_type"):
        return f"must be a list{got}"
    if kind in ("model_type", "dict_type", "model_attributes_type"):
        return f"must be a mapping{got}"
    if kind == "literal_error":
        return f"must be one of {ctx.get('expected')}{got}"
    if kind == "value_error":
        return str(error["msg"]).removeprefix("Value error, ")
    return f"{error['msg']}{got}"
