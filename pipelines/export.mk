# Exports of a pipeline run for other tools (docs/FORMATS.md, "Exported sequences"): the final
# transfers (gpr-nn+correct+stitch) and the variations the report shows, each as NAME.glb and
# NAME.obj + NAME.pc2 under OUT/export/, at the sequence's own frame rate (its rate.json).
# `make transfer` and `make variation` end with it.
#   make export OUT=out
EXPORT_TRANSFERS = $(wildcard $(OUT)/transfer/*/*/gpr-nn+correct+stitch)
EXPORT_VARIATIONS = $(foreach v,$(VARIATION_REPORT_VIEWS),$(lastword $(subst =, ,$(v))))

.PHONY: export
export: $(STAGE_BINARIES)
	@for d in $(EXPORT_TRANSFERS) $(EXPORT_VARIATIONS); do \
	  test -d "$$d" || continue; \
	  case "$$d" in \
	    $(OUT)/transfer/*) rel=$${d#$(OUT)/transfer/}; o=$(OUT)/export/transfer/$${rel%/*} ;; \
	    *) rel=$${d#$(OUT)/}; o=$(OUT)/export/$$rel ;; \
	  esac; \
	  mkdir -p "$$(dirname "$$o")" && \
	  $(BIN)/mesh-export "$$d" --out "$$o.glb" && $(BIN)/mesh-export "$$d" --out "$$o.pc2" || exit 1; \
	  echo "mesh-export $$o.glb, $$o.obj + $$o.pc2" >&2; \
	done
