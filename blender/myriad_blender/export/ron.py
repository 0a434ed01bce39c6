"""Writing myriad's RON scene format (docs/scene-format.md): numbers, vectors, strings and
the `Name(field: value, ...)` records it is made of."""


def num(x):
    """A number as RON reads it (always with a decimal point or exponent for floats)."""
    x = float(x)
    if x != x or x in (float("inf"), float("-inf")):
        raise ValueError(f"{x} is not a finite number")
    text = repr(x)
    return text


def vec(v):
    """A tuple of numbers."""
    return "(" + ", ".join(num(x) for x in v) + ")"


def string(s):
    """A quoted string."""
    return '"' + str(s).replace("\\", "\\\\").replace('"', '\\"') + '"'


def record(name, **fields):
    """`Name(field: value, ...)`; `None` values are left out (optional fields)."""
    parts = [f"{k}: {v}" for k, v in fields.items() if v is not None]
    return f"{name}(" + ", ".join(parts) + ")"


def scene(camera, film, render, objects, lights, environment):
    """The whole file."""
    lines = ["Scene(", f"    camera: {camera},", f"    film: {film},", f"    render: {render},"]
    if objects:
        lines.append("    objects: [")
        lines += [f"        {o}," for o in objects]
        lines.append("    ],")
    if lights:
        lines.append("    lights: [")
        lines += [f"        {light}," for light in lights]
        lines.append("    ],")
    if environment is not None:
        lines.append(f"    environment: {environment},")
    lines.append(")")
    return "\n".join(lines) + "\n"
