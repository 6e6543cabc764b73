"""``python -m ppamsafety.sections``: print the README's table of the report sections."""

from . import readme_table

if __name__ == "__main__":
    print(readme_table())
