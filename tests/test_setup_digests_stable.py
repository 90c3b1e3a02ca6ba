"""A built-in setup digests as it did before fields with defaults were added to the setup
schema (``bench``, ``specimen.layers``, ``specimen.shear_legs``): a result's recorded
digest (``calibrate --from`` checks it) stays valid across such additions.

The digests below were computed by the code of commit 007c16a.  If a built-in setup's
physics is changed on purpose, its digest changes: update the value here and say so in
the CHANGELOG (results recorded on the old setup then need ``--current-setup``).
"""

from __future__ import annotations

import pytest

from echocal.setup_digest import setup_digest

DIGESTS = {
    "thesis": "3c16930426a8b34c42cddd1a56348e5403f97bcf45375110c5dc548d93490255",
    "immersion-5mhz": "a824f9858e26ef57db3c2a5de339323164a9a0c1a539a432223e897a11429f19",
    "immersion-layered": "0a43137a8ac528f2c2546a145c44f33b530e4fc203ae37920c40b6ee486c6b52",
    "scan-5mhz": "e63cc0df1ae56e5702bb3b6fa8750411123b18ccc869eb3f092999d52acca1e8",
}


@pytest.mark.parametrize("name", sorted(DIGESTS))
def test_a_built_in_setup_digests_as_before(name: str) -> None:
    assert setup_digest(name)["sha256"] == DIGESTS[name], (
        f"{name}: its digest changed; a field added with a default must be left out of "
        "setups.reading.resolved_data while it has its default"
    )
