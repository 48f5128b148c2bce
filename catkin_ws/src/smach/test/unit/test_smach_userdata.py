"""UserData and Remapper: access, remapping, read-only inputs, undeclared keys, by-reference data."""
import pickle

import pytest

import smach


def test_userdata_attribute_and_item_access():
    ud = smach.UserData()
    ud.a = 1
    ud["b"] = 2
    assert ud["a"] == 1 and ud.b == 2
    assert "a" in ud and "zz" not in ud
    assert sorted(ud.keys()) == ["a", "b"]
    assert ud._data == {"a": 1, "b": 2}


def test_userdata_missing_key_raises_keyerror():
    ud = smach.UserData()
    with pytest.raises(KeyError):
        ud.missing
    with pytest.raises(KeyError):
        ud["missing"]


def test_userdata_update_from_userdata_and_dict():
    a, b = smach.UserData(), smach.UserData()
    b.x = 1
    a.update(b)
    a.update({"y": 2})
    assert a.x == 1 and a.y == 2


def test_userdata_pickles_and_copies():
    import copy
    ud = smach.UserData()
    ud.x = [1]
    ud2 = pickle.loads(pickle.dumps(ud))
    assert ud2.x == [1]
    ud3 = copy.copy(ud)
    assert ud3.x == [1]
    ud3.y = 2
    assert ud3.y == 2


def test_userdata_extract_and_merge():
    ud = smach.UserData()
    ud.parent_name = 3
    ex = ud.extract(["parent_name"], {"child": "parent_name"})
    assert ex.child == 3
    other = smach.UserData()
    other.local = 7
    ud.merge(other, ["local"], {"local": "parent_local"})
    assert ud.parent_local == 7


def test_remapper_maps_names_both_ways():
    ud = smach.UserData()
    ud.parent_in = 1
    r = smach.Remapper(ud, ["x"], ["y"], {"x": "parent_in", "y": "parent_out"})
    assert r.x == 1 and r["x"] == 1
    r.y = 5
    assert ud.parent_out == 5
    r["y"] = 6
    assert ud.parent_out == 6
    assert r.keys() == ["x"]  # the state's own name, not the parent's
    assert "x" in r and "y" in r and "parent_in" not in r


def test_remapper_undeclared_read_raises_invalid_user_code_and_keyerror():
    ud = smach.UserData()
    ud.secret = 1
    r = smach.Remapper(ud, [], [], {})
    with pytest.raises(smach.InvalidUserCodeError):
        r.secret
    with pytest.raises(KeyError):
        r["secret"]


def test_remapper_undeclared_write_is_refused_and_logged(quiet_logs):
    ud = smach.UserData()
    ud.x = 1
    r = smach.Remapper(ud, ["x"], [], {})
    r.x = 2
    assert ud.x == 1
    assert any("Writing to SMACH userdata key 'x'" in m for m in quiet_logs["error"])


def test_remapper_input_only_objects_are_read_only_but_mutable_containers_by_reference():
    class Obj:
        def __init__(self):
            self.v = 1

        def double(self):
            return self.v * 2

    ud = smach.UserData()
    ud.obj = Obj()
    ud.lst = [1]
    r = smach.Remapper(ud, ["obj", "lst"], [], {})
    assert r.obj.v == 1 and r.obj.double() == 2
    with pytest.raises(TypeError):
        r.obj.v = 3
    assert ud.obj.v == 1
    r.lst.append(2)  # lists are passed by reference (upstream)
    assert ud.lst == [1, 2]
    rw = smach.Remapper(ud, ["obj"], ["obj"], {})
    rw.obj.v = 9
    assert ud.obj.v == 9
    assert rw.obj is ud.obj


def test_remapper_update_writes_only_declared_keys():
    ud = smach.UserData()
    r = smach.Remapper(ud, [], ["a"], {"a": "pa"})
    r.update({"a": 1, "b": 2})
    assert ud._data == {"pa": 1}
