"""Shared by the JSON loaders' corruption properties (device, calibration files)."""
from hypothesis import strategies as st

# any JSON value, nested a little: what a corrupted field may hold
json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**6), 10**6) | st.floats() | st.text(max_size=5),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=5), children, max_size=4),
    max_leaves=8,
)


def json_paths(obj, prefix=()):
    """Every path (tuple of keys and indices) into obj, the root () included."""
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from json_paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from json_paths(v, prefix + (i,))
