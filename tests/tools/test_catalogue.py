"""tools.catalogue: it regenerates the schema's enums and the converter table, and finds nothing to do on
the tree as committed."""

from __future__ import annotations

import json

from airsim_mapper.common.resources import SCHEMA_PATH
from airsim_mapper.convert.catalog import CONVERTERS
from tools import catalogue


def test_the_committed_schema_and_table_are_what_the_catalogue_makes():
    assert catalogue.main(["--check"]) == 0


def test_a_schema_missing_a_converter_gets_it_back_and_nothing_else_changes():
    text = SCHEMA_PATH.read_text(encoding="utf-8")
    schema = json.loads(text)
    schema["$defs"]["converter"]["enum"].remove("odometry")
    schema["$defs"]["for_each"]["enum"].reverse()
    damaged = json.dumps(schema, indent=2, ensure_ascii=False) + "\n"
    assert catalogue.schema_text(damaged) == text
    assert json.loads(text)["$defs"]["converter"]["enum"] == list(CONVERTERS)


def test_the_table_between_the_markers_is_replaced_and_the_prose_kept():
    text = f"intro\n{catalogue.BEGIN}\n| old |\n{catalogue.END}\nsteps\n"
    made = catalogue.doc_text(text)
    assert made.startswith(f"intro\n{catalogue.BEGIN}\n| converter |") and made.endswith(
        f"{catalogue.END}\nsteps\n"
    )
    assert "`odometry`" in made
