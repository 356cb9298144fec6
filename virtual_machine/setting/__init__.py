"""The setting sheets: the seeds' formulas per structure, change gears, realised chain ratios, the lathe's layout."""
