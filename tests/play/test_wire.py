"""What travels between carom play's server and page (carom.play.wire)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from carom.play.wire import MAX_MESSAGE, Refused, check_setting, pack, read_command, unpack


def test_pack_and_unpack_round_trip() -> None:
    arrays = {
        "x": np.arange(12, dtype=np.float32).reshape(6, 2),
        "state": np.array([1, 3, 0], np.uint8),  # 3 bytes: the next array starts at 8
        "n": np.array([-1, 7], np.int32),
        "d": np.array([np.pi]),
    }
    message = pack({"type": "frame", "time": 0.5}, arrays)
    assert message[:4] == b"CRM1"
    header, out = unpack(message)
    assert header == {"type": "frame", "time": 0.5}
    for name, a in arrays.items():
        np.testing.assert_array_equal(out[name], a)
        assert out[name].dtype == a.dtype
    # every array starts on a multiple of 8 bytes: the page reads it as a typed array in place
    size = int.from_bytes(message[4:8], "little")
    table = json.loads(message[8 : 8 + size])["arrays"]
    assert (8 + size) % 8 == 0
    assert all(offset % 8 == 0 for _, _, _, offset in table)


def test_pack_refuses_what_the_page_cannot_read() -> None:
    with pytest.raises(TypeError, match="dtype"):
        pack({}, {"c": np.zeros(2, np.complex128)})
    with pytest.raises(ValueError, match="Out of range float"):
        pack({"t": float("nan")}, {})


def read(text: str, dim: int = 2):  # type: ignore[no-untyped-def]
    return read_command(text, dim, reach=1000.0, top_speed=100.0)


def test_good_commands() -> None:
    c = read('{"op": "shoot", "point": [1, 2.5], "velocity": [3, -4]}')
    assert c.op == "shoot"
    np.testing.assert_array_equal(c.fields["point"], [1.0, 2.5])
    c = read('{"op": "grab", "point": [0, 0, 9], "direction": [0, 0, -2]}', dim=3)
    np.testing.assert_array_equal(c.fields["direction"], [0.0, 0.0, -1.0])  # made a unit
    assert read('{"op": "slow", "factor": 0.25}').fields["factor"] == 0.25
    assert read('{"op": "draw", "name": "boxes", "on": true}').fields == {
        "name": "boxes",
        "on": True,
    }


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ('{"op": "grab", "point": [NaN, 1]}', "NaN is not a number"),
        ('{"op": "grab", "point": [Infinity, 1]}', "Infinity is not a number"),
        ('{"op": "grab", "point": [1e400, 1]}', "finite"),
        ('{"op": "grab", "point": [1, 2, 3]}', "list of 2 numbers"),
        ('{"op": "grab", "point": [1, "2"]}', "list of 2 numbers"),
        ('{"op": "grab", "point": [true, 2]}', "list of 2 numbers"),
        ('{"op": "grab", "point": [5000, 2]}', "within 1000"),
        ('{"op": "shoot", "point": [1, 2], "velocity": [1e6, 0]}', "at most 100 m/s"),
        ('{"op": "shoot", "point": [1, 2]}', "needs ['velocity']"),
        ('{"op": "pause", "now": 1}', "not ['now']"),
        ('{"op": "fly"}', "unknown op"),
        ('{"op": 3}', 'an "op"'),
        ("[1, 2]", 'an "op"'),
        ("{not json", "not JSON"),
        ('{"op": "slow", "factor": 0.3}', "one of"),
        ('{"op": "scene", "name": 7}', "a scene's name"),
        ('{"op": "set", "name": "mass", "value": 1}', "one of"),
        ('{"op": "draw", "name": "boxes", "on": 1}', "true or false"),
        ('{"op": "grab", "point": [0, 0, 1], "direction": [0, 0, 0]}', "not be zero"),
    ],
)
def test_bad_commands_are_refused_with_why(text: str, says: str) -> None:
    dim = 3 if '"direction"' in text else 2
    with pytest.raises(Refused, match=r".*" + __import__("re").escape(says)):
        read(text, dim)


def test_long_and_binary_messages_are_refused() -> None:
    with pytest.raises(Refused, match="at most"):
        read('{"op": "pause", "x": "' + "a" * MAX_MESSAGE + '"}')
    with pytest.raises(Refused, match="JSON text"):
        read_command(b'{"op": "pause"}', 2, 1.0, 1.0)


def test_settings_ranges() -> None:
    assert check_setting("gravity", 9.81) == 9.81
    assert check_setting("substeps", 8.0) == 8.0
    with pytest.raises(Refused, match="whole number"):
        check_setting("substeps", 2.5)
    with pytest.raises(Refused, match="between 0 and 1"):
        check_setting("restitution", 1.5)
    with pytest.raises(Refused, match="between"):
        check_setting("friction", float("nan"))
