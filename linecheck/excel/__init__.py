"""Excel design sheets (front-end side: imports openpyxl; never imported by the core).

:func:`write_workbook` writes the workbook of one or more run result documents
(typed :class:`~linecheck.io.document.RunDocument`, or their saved JSON read through
``RunDocument.from_json``); ``linecheck run --excel``,
``linecheck batch --excel`` and ``linecheck export`` all call it.
"""

from .writer import check_excel_target, load_result_docs, write_workbook

__all__ = ["check_excel_target", "load_result_docs", "write_workbook"]
