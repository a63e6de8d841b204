"""The colour-map tests' `addon` fixture: the add-on registered on a factory
scene, lookup images written next to the test's files."""

import pytest

import penumbra


@pytest.fixture
def addon(factory_scene):
    penumbra.register()
    factory_scene.penumbra.colormap.output_folder = ""
    yield factory_scene
    penumbra.unregister()
