"""The operators (``turning.*``): thin leaves that are registered and nothing imports; what
several operators share lives in the other subpackages."""
