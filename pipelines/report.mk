# The HTML report of a pipeline run: OUT/index.html plus OUT/report-assets/, opened from disk
# (no server, no network). Lists the tables (results.json, variation.json), contact sheets, GIFs,
# plots and artifact provenance found under OUT; REPORT_VIEWS adds the 3D player, side by side.
#   make report OUT=out
#   make report OUT=out REPORT_VIEWS="source=set/A/test/walk transfer=out/transfer/A-to-B/walk/gpr-nn truth=set/truth/B/walk"
REPORT_VIEWS ?=
REPORT_TITLE ?= surfcap report: $(OUT)

.PHONY: report setup-web
# npm packages (three, gltf-validator, playwright-core) and Debian chromium; no-op when present.
setup-web:
	@scripts/setup-web

report: $(STAGE_BINARIES) setup-web
	$(BIN)/html-report --out $(OUT) --title "$(REPORT_TITLE)" $(foreach v,$(REPORT_VIEWS),--view $(v))
