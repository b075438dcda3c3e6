"""Widget outputs of an executed notebook as static HTML, for the reports.

An executed notebook keeps its widgets as ``application/vnd.jupyter.widget-view+json``
outputs that point at models in ``metadata.widgets`` (the final widget state papermill /
nbclient store, ``store_widget_state``). Without a kernel these only render through the
widgets HTML manager, a JavaScript bundle nbconvert loads from a CDN: no network, no
figures ("model not found" / "Error displaying widget"). :func:`freeze_widgets` instead
replaces each widget output by the HTML of its final state, so a report page shows the
panels' last figures with no script at all:

* boxes become ``div`` blocks of their visible children;
* an ``Image`` becomes an ``<img>`` with its PNG inline (a data URL);
* ``HTML`` / ``Label`` widgets keep their HTML / text (less a panel's update timing, a
  :data:`TIMING_CLASS` span);
* value controls (sliders, dropdowns, text boxes, ...) become ``description: value``
  lines, so the reader sees the settings the figures were made with;
* ``Output`` widgets show their PNG, HTML and text outputs; buttons are dropped.

The widget state is removed from the metadata afterwards, so nbconvert does not add its
widget loader (the CDN script) to the page.
"""

from __future__ import annotations

import html
import re

__all__ = ["TIMING_CLASS", "WIDGET_STATE", "WIDGET_VIEW", "freeze_widgets", "widget_html"]

WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
WIDGET_STATE = "application/vnd.jupyter.widget-state+json"
_BOXES = {"VBoxModel": "column", "HBoxModel": "row", "BoxModel": "column",
          "GridBoxModel": "row"}
TIMING_CLASS = "navlib-timing"
"""Class of the spans a panel's status line gives its own update timing: internal, left out
of report pages."""
_TIMING = re.compile(rf'[;,]?\s*<span class="{TIMING_CLASS}">.*?</span>', re.S)
_IMG_STYLE = "max-width:100%;height:auto"
"""Style of a frozen figure: at most the page's width, always at its own aspect ratio."""
_SKIPPED = {"ButtonModel", "LayoutModel", "DescriptionStyleModel", "SliderStyleModel",
            "ButtonStyleModel", "ProgressStyleModel", "StyleModel"}


def _ref(value) -> str | None:
    return value[len("IPY_MODEL_"):] if isinstance(value, str) and \
        value.startswith("IPY_MODEL_") else None


def _hidden(state: dict, models: dict) -> bool:
    layout = models.get(_ref(state.get("layout")) or "", {}).get("state", {})
    return layout.get("display") == "none" or layout.get("visibility") == "hidden"


def _buffer(model: dict, name: str) -> str | None:
    for buffer in model.get("buffers", ()):
        if buffer.get("path") == [name] and buffer.get("encoding") == "base64":
            return buffer["data"]
    return None


def _control_value(state: dict) -> str:
    labels = state.get("_options_labels")
    index = state.get("index")
    if labels is not None and index is not None:
        chosen = [labels[i] for i in index] if isinstance(index, list) else [labels[index]]
        return ", ".join(chosen)
    value = state.get("value")
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return " – ".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in value)
    return str(value)


def _outputs_html(outputs) -> str:
    parts = []
    for out in outputs:
        data = out.get("data", {})
        if "image/png" in data:
            parts.append(f'<img style="{_IMG_STYLE}" src="data:image/png;base64,'
                         f'{data["image/png"]}">')
        elif "text/html" in data:
            html_data = data["text/html"]
            parts.append("".join(html_data) if isinstance(html_data, list) else html_data)
        elif "text/plain" in data or out.get("output_type") == "stream":
            text = data.get("text/plain", out.get("text", ""))
            text = "".join(text) if isinstance(text, list) else text
            parts.append(f"<pre>{html.escape(text)}</pre>")
    return "".join(parts)


def widget_html(model_id: str, models: dict, depth: int = 0) -> str:
    """Static HTML of the widget ``model_id`` and its children in the final state
    ``models`` (the ``state`` mapping of a widget-state document)."""
    model = models.get(model_id)
    if model is None or depth > 50:
        return ""
    name = model.get("model_name", "")
    state = model.get("state", {})
    if name in _SKIPPED or _hidden(state, models):
        return ""
    classes = " ".join(state.get("_dom_classes", ()))
    if name in _BOXES:
        children = "".join(widget_html(_ref(c) or "", models, depth + 1)
                           for c in state.get("children", ()))
        # align-items: flex-start, not the default stretch: a stretched <img> in a column
        # box takes the box's width at its own height (a panel figure drawn 2x wide)
        return (f'<div class="navlib-static {classes}" style="display:flex;'
                f'flex-direction:{_BOXES[name]};gap:4px;flex-wrap:wrap;'
                f'align-items:flex-start">{children}</div>')
    if name == "ImageModel":
        data = _buffer(model, "value")
        fmt = state.get("format", "png")
        return (f'<img class="{classes}" style="{_IMG_STYLE}" '
                f'src="data:image/{fmt};base64,{data}">') if data else ""
    if name in ("HTMLModel", "HTMLMathModel"):
        return f'<div class="{classes}">{_TIMING.sub("", state.get("value", ""))}</div>'
    if name == "LabelModel":
        return f"<div>{html.escape(str(state.get('value', '')))}</div>"
    if name == "OutputModel":
        return f'<div class="{classes}">{_outputs_html(state.get("outputs", ()))}</div>'
    if "value" in state or "index" in state:
        description = html.escape(str(state.get("description", "")))
        return (f'<div class="navlib-static-control" style="font-size:14px">'
                f"<b>{description}</b> {html.escape(_control_value(state))}</div>")
    return ""


def freeze_widgets(nb) -> int:
    """Replace the widget outputs of notebook ``nb`` (nbformat node, changed in place) by
    the static HTML of their final state, and drop the widget state from its metadata.

    Returns the number of outputs replaced. Outputs whose model is not in the state keep
    their text fallback only.
    """
    document = nb.metadata.get("widgets", {}).get(WIDGET_STATE, {})
    models = document.get("state", {})
    replaced = 0
    for cell in nb.cells:
        for out in cell.get("outputs", ()):
            data = out.get("data", {})
            if WIDGET_VIEW not in data:
                continue
            model_id = data[WIDGET_VIEW].get("model_id", "")
            frozen = widget_html(model_id, models)
            del data[WIDGET_VIEW]
            if frozen:
                data["text/html"] = frozen
                data.pop("text/plain", None)
                replaced += 1
    nb.metadata.pop("widgets", None)
    return replaced
