"""Ships the top-level models/ and problems/ inside the package, as
design/shipped/models and design/shipped/problems (data-only packages), so
that an installed toolkit (``pip install .``, a wheel) finds them where
design/io/files.py looks. An editable install reads them from the checkout.
The rest of the configuration is in pyproject.toml."""

from setuptools import find_namespace_packages, find_packages, setup

SHIPPED = {f"design.shipped.{folder}": folder for folder in ("models", "problems")}
DATA_PACKAGES = [*SHIPPED, *(f"{name}.{sub}" for name, folder in SHIPPED.items()
                             for sub in find_namespace_packages(where=folder))]

setup(packages=find_packages(include=["design", "design.*"]) + DATA_PACKAGES,
      package_dir=SHIPPED,
      package_data={name: ["*.yaml"] for name in DATA_PACKAGES})
