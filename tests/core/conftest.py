import pytest
from helpers import toy_plugin


@pytest.fixture
def toys():
    with toy_plugin():
        yield


@pytest.fixture
def log(tmp_path):
    return tmp_path / "executions.log"


@pytest.fixture
def cache(tmp_path):
    return tmp_path / "cache"
