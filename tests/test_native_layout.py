"""The native FMUs' data layout and limits are named once, in fmus/native/pcs_layout.h and
pcs_limits.h: the C readers use every field by name and no position by number, the Python
writer packs exactly the named fields, and the limits agree with the Python size guard."""

import re

import numpy as np
import pytest

from pantocosim.master.native.headers import SOURCE_DIR, fields, header_numbers, pack, unpack

SECTIONS = {"LIN_SIZE": "LIN_SIZES", "MOD_SIZE": "MOD_SIZES", "PAN_SIZE": "PAN_SIZES",
            "PAN_SCALAR": "PAN_SCALARS", "NLP_SCALAR": "NLP_SCALARS"}


def c_sources() -> str:
    return "\n".join(p.read_text() for p in sorted(SOURCE_DIR.glob("*.c")))


@pytest.mark.parametrize("prefix", sorted(SECTIONS))
def test_each_section_is_numbered_without_a_gap(prefix):
    numbers = header_numbers("pcs_layout.h")
    assert len(fields(prefix)) == numbers[SECTIONS[prefix]]


def test_the_catenary_scalars_are_shared_and_the_modal_ones_follow():
    numbers = header_numbers("pcs_layout.h")
    assert len(fields("CAT_SCALAR")) == numbers["LIN_SCALARS"]
    assert len(fields("CAT_SCALAR", "MOD_SCALAR")) == numbers["MOD_SCALARS"]


def test_the_c_readers_use_every_field_by_name_and_no_position_by_number():
    text = c_sources()
    prefixes = tuple(f"{p}_" for p in [*SECTIONS, "CAT_SCALAR", "MOD_SCALAR"])
    names = [n for n in header_numbers("pcs_layout.h") if n.startswith(prefixes)]
    assert len(names) > 50
    for name in names:
        assert name in text, f"{name} is read nowhere"
    literal = re.findall(r"\b(?:sizes|sc)\[\d+\]", text)
    assert literal == []


def test_the_writer_packs_exactly_the_named_fields():
    names = fields("PAN_SCALAR")
    values = {n: float(i) for i, n in enumerate(names)}
    section = pack(values, np.float64, "PAN_SCALAR")
    assert unpack(section, "PAN_SCALAR") == values
    with pytest.raises(ValueError, match="pcs_layout.h"):
        pack({**values, "EXTRA": 1.0}, np.float64, "PAN_SCALAR")
    with pytest.raises(ValueError, match="pcs_layout.h"):
        pack({n: v for n, v in values.items() if n != "STEP"}, np.float64, "PAN_SCALAR")
    with pytest.raises(ValueError, match="pcs_layout.h"):
        unpack(section[:-1], "PAN_SCALAR")


def test_the_kinds_and_limits_are_the_headers():
    from pantocosim.catenary.size_guard import MAX_DOFS
    from pantocosim.master.native.data_file import KINDS
    from pantocosim.master.native.models import MAX_SUPPORTS

    data = header_numbers("pcs_data.h")
    assert KINDS == {"linear": data["PCS_KIND_LINEAR_CATENARY"],
                     "modal": data["PCS_KIND_MODAL_CATENARY"],
                     "lumped": data["PCS_KIND_LUMPED_PANTOGRAPH"],
                     "dsa380-rigid": data["PCS_KIND_DSA380_RIGID"],
                     "dsa380-flexible": data["PCS_KIND_DSA380_FLEXIBLE"]}
    assert header_numbers("pcs_limits.h")["PCS_MAX_DOFS"] == MAX_DOFS
    assert MAX_SUPPORTS == header_numbers("catenary_vars.h")["CAT_MAX_SUPPORTS"]
