"""The widget's option fields, made from the option definitions (:mod:`skelprune.options`):
one field per option, its default shown, its help text as the tool tip; reading them
back gives the keyword values the options classes check."""

from __future__ import annotations

from dataclasses import fields
from typing import Any

from qtpy.QtWidgets import QCheckBox, QComboBox, QFormLayout, QLineEdit, QWidget

from ..errors import InvalidOptionError
from ..options import option_fields

__all__ = ["OptionForm"]


class OptionForm(QWidget):
    """A form of the options of ``groups`` (option classes), less those in ``skip``."""

    def __init__(self, *groups: type, skip: tuple[str, ...] = ()) -> None:
        super().__init__()
        layout = QFormLayout(self)
        kinds = {f.name: str(f.type) for group in groups for f in fields(group)}
        self.fields: dict[str, QWidget] = {}
        self._kinds: dict[str, str] = {}
        for name, default, help_text, choices in option_fields(*groups):
            if name in skip:
                continue
            field: QWidget
            if choices is not None:
                field = QComboBox()
                field.addItems(list(choices))
                # a choice whose library value is None is spelled "none"
                field.setCurrentText("none" if default is None else str(default))
            elif isinstance(default, bool):
                field = QCheckBox()
                field.setChecked(default)
            else:
                field = QLineEdit("" if default is None else f"{default:g}")
                field.setPlaceholderText("default (see the tip)")
            field.setToolTip(help_text)
            field.setObjectName(name)
            layout.addRow(name, field)
            label = layout.labelForField(field)
            if label is not None:
                label.setToolTip(help_text)
            self.fields[name] = field
            self._kinds[name] = "int" if kinds[name].startswith("int") else "float"

    def values(self) -> dict[str, Any]:
        """Every option's value as typed (an empty number is left out: the option's
        default); a number that does not parse is an :class:`InvalidOptionError` naming
        it."""
        out: dict[str, Any] = {}
        for name, field in self.fields.items():
            if isinstance(field, QComboBox):
                out[name] = field.currentText()
            elif isinstance(field, QCheckBox):
                out[name] = field.isChecked()
            elif isinstance(field, QLineEdit):
                text = field.text().strip()
                if text:
                    out[name] = self._number(name, text)
        return out

    def _number(self, name: str, text: str) -> float | int:
        try:
            return int(text) if self._kinds[name] == "int" else float(text)
        except ValueError:
            kind = "a whole number" if self._kinds[name] == "int" else "a number"
            raise InvalidOptionError(f"{name} must be {kind}, got {text!r}") from None
