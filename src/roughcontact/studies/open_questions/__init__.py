"""The paper's open questions answered on published runs (docs/open-questions/).

:mod:`.analysis` holds the numbers (pure functions over a contact aggregate), :mod:`.claims` the
answers' rows and their printed rules, :mod:`.figures` the figures and :mod:`.page` the
``regenerate`` / ``publish`` commands (``python -m roughcontact.studies.open_questions``).
"""

from .claims import RULES
from .page import DATA_FILES, main, markdown_table, publish, regenerate

__all__ = ["RULES", "DATA_FILES", "main", "markdown_table", "publish", "regenerate"]
