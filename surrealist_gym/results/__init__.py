"""A command's results: the folder it writes (:class:`ResultsFolder`: made, locked, resumed, kept on failure) and
what a search writes in it (:mod:`.search`: best test, evaluations.csv, summary.json, plots; :func:`export_test`,
which the competition's suite export uses too)."""
from .folder import EVALUATIONS, LOCK_FILE, RUN_FILE, ResultsFolder, count_rows, read_json, read_summary
from .search import (
                     FILES_FOLDER,
                     README_TITLE,
                     export_test,
                     plot_search,
                     search_goal,
                     search_profiles,
                     write_evaluations_csv,
                     write_results,
)

__all__ = ["EVALUATIONS", "FILES_FOLDER", "LOCK_FILE", "README_TITLE", "RUN_FILE", "ResultsFolder", "count_rows",
           "export_test", "plot_search", "read_json", "read_summary", "search_goal", "search_profiles",
           "write_evaluations_csv", "write_results"]
