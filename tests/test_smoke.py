from core.errors import DeviceError, DeviceTimeoutError


def test_error_names_device_and_code():
    err = DeviceTimeoutError("hande", "no answer from slave 9", code=0x0B)
    assert isinstance(err, DeviceError)
    assert "hande" in str(err) and "11" in str(err)
