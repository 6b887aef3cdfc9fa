"""The viewer inline in Jupyter: in a real IPython kernel (ipykernel, driven by nbclient as a
notebook front end is), ``vtksvdag.view(..., block=False)`` returns at once with the server
running on the kernel's event loop, and the cell's rich output (the iframe a notebook shows) is
the application: loaded in headless chromium as a notebook page would, its frame shows the 3-D
image and the segment list, served while the kernel waits for its next cell."""
import re

import pytest

from conftest import REPO

pytest.importorskip("trame", reason="the viewer extra (pip install .[viewer]) is not installed")
nbclient = pytest.importorskip("nbclient", reason="nbclient is not installed")
nbformat = pytest.importorskip("nbformat", reason="nbformat is not installed")
pytest.importorskip("ipykernel", reason="ipykernel is not installed")
from selenium.webdriver.common.by import By  # noqa: E402

from test_viewer_browser import DATA, SIZE, _wait_for_image, browser  # noqa: E402,F401

CELL = f"""
import vtksvdag
app = vtksvdag.view({str(DATA)!r}, block=False, open_browser=False, size={SIZE!r})
app
"""


def test_inline_in_a_kernel(browser, tmp_path):  # noqa: F811 (the fixture)
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(CELL)])
    client = nbclient.NotebookClient(notebook, kernel_name="python3", timeout=120,
                                     resources={"metadata": {"path": str(REPO)}})
    with client.setup_kernel():
        client.execute_cell(notebook.cells[0], 0)
        outputs = notebook.cells[0].outputs
        html = [o["data"]["text/html"] for o in outputs if "text/html" in o.get("data", {})]
        assert html, outputs
        assert re.search(r'<iframe src="http://127\.0\.0\.1:\d+/', html[0]), html[0]
        page = tmp_path / "notebook.html"
        page.write_text(f"<html><body>{html[0]}</body></html>")
        browser.get(page.as_uri())
        browser.switch_to.frame(browser.find_element(By.TAG_NAME, "iframe"))
        try:
            _wait_for_image(browser)
            rows = browser.find_elements(By.CSS_SELECTOR,
                                         '[data-testid="svdag-segment-list"] [data-label]')
            assert len(rows) > 0
        finally:
            browser.switch_to.default_content()
