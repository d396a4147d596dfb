# A package, so that this conftest is `validation.conftest` and does not replace tests/integration/python's
# `conftest` (which its tests import by that name) when pytest runs both folders at once.
