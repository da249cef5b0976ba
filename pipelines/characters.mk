# make characters-data: capture sets from real animated game characters (OpenArena's Quake 3 MD3
# players, fetched by `make assets`), one per pair: $(OUT)/characters/sarge-sorceress and
# $(OUT)/characters/major-liz (frames, fps and key-poses only, the target's own performance of each
# test motion under reference/; docs/DATA.md, "Animated characters").
CHARACTERS := $(OUT)/characters

.PHONY: characters-data

characters-data: $(CHARACTERS)/sarge-sorceress/set.json

$(CHARACTERS)/sarge-sorceress/set.json: | build assets
	$(BIN)/characters -q --out $(CHARACTERS)
