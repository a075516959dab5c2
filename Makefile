# `make demo` and `make test` do everything on a fresh machine.
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
STAMP   = $(VENV)/.installed-$(shell sha1sum pyproject.toml | cut -c1-12)
OUT    ?= nilpotent-paper

.PHONY: demo test lint bench docs venv clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	rm -f $(VENV)/.installed-*
	touch $(STAMP)

# `make docs` needs only the package and the site's tools (the `docs` extra), not the
# test toolchain
DOCS_STAMP = $(VENV)/.docs-$(shell sha1sum pyproject.toml | cut -c1-12)

$(DOCS_STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet -e ".[docs]"
	rm -f $(VENV)/.docs-*
	touch $(DOCS_STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/nilpotent reproduce --out $(OUT)
	@echo "open $(OUT)/index.html"

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks examples docs/hooks

export NO_MKDOCS_2_WARNING := 1

test: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks examples docs/hooks
	$(VENV)/bin/pytest -n 2 --dist loadfile --nbmake tests docs/tutorial.ipynb
	$(VENV)/bin/mkdocs build --strict --site-dir build/site
	$(VENV)/bin/pyright --pythonpath $(PY) src

docs: $(DOCS_STAMP)
	$(VENV)/bin/mkdocs build --strict --site-dir build/site
	@echo "open build/site/index.html"

bench: $(STAMP)
	for b in benchmarks/*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) build dist src/*.egg-info .pytest_cache .ruff_cache $(OUT)
