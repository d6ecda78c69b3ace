"""The engine on a billiard table (paper section 7): systems, contacts, resolution, the run loop."""

from .driver import simulate_table
from .result import IMPACT_COLUMNS, TableResult, impact_table

__all__ = ["IMPACT_COLUMNS", "TableResult", "impact_table", "simulate_table"]
