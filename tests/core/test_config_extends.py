"""A configuration file that builds on a base file (``extends:``, core.config)."""

import pytest

from core.config import ConfigError, load_yaml_extending


def write(folder, name, text):
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_the_file_is_laid_over_its_base_key_by_key(tmp_path):
    write(tmp_path, "base/common.yaml",
          "a: 1\nnested: {x: 1, y: 2, deep: {p: 1, q: 2}}\nlist: [1, 2, 3]\n")  # fmt: skip
    top = write(tmp_path, "top.yaml", "extends: base/common.yaml\nnested: {y: 5, deep: {q: 9}}\n"
                "list: [7]\nnew: true\n")  # fmt: skip
    assert load_yaml_extending(top) == {
        "a": 1,
        "nested": {"x": 1, "y": 5, "deep": {"p": 1, "q": 9}},
        "list": [7],  # a list replaces the base's whole
        "new": True,  # a key the base lacks is kept: the schema's build judges it
    }


def test_bases_chain_and_a_file_without_extends_is_itself(tmp_path):
    write(tmp_path, "grand.yaml", "a: 1\nb: 1\nc: 1\n")
    write(tmp_path, "parent.yaml", "extends: grand.yaml\nb: 2\n")
    child = write(tmp_path, "child.yaml", "extends: parent.yaml\nc: 3\n")
    assert load_yaml_extending(child) == {"a": 1, "b": 2, "c": 3}
    assert load_yaml_extending(tmp_path / "grand.yaml") == {"a": 1, "b": 1, "c": 1}


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("extends: missing.yaml\n", "key 'extends': no such base file"),
        ("extends: 3\n", "key 'extends': expected the path of a base .yaml file, got 3"),
        ("extends: top.yaml\n", "key 'extends': top.yaml extends this file (a cycle)"),
    ],
)
def test_a_bad_base_is_one_line_naming_the_file_and_key(tmp_path, text, expected):
    top = write(tmp_path, "top.yaml", text)
    with pytest.raises(ConfigError) as info:
        load_yaml_extending(top)
    message = str(info.value)
    assert message.startswith(f"{top}: ") and expected in message and "\n" not in message


def test_a_longer_cycle_is_refused(tmp_path):
    write(tmp_path, "a.yaml", "extends: b.yaml\nx: 1\n")
    write(tmp_path, "b.yaml", "extends: a.yaml\nx: 2\n")
    with pytest.raises(ConfigError, match="a cycle"):
        load_yaml_extending(tmp_path / "a.yaml")
