"""Filters: python-can's can_filters in the channel's acceptance filter and ID list where the
VCI filter can express them, in software otherwise."""

from __future__ import annotations

from . import _vci
from ._calls import _call, _vci_errors


class _FilterMixin:
    """CanemuBus's filters. Uses the bus's _channel and _initializing; sets _hw_filtered, which
    _recv_internal hands to python-can."""

    def _apply_filters(self, filters) -> None:
        """Filters in the channel where the VCI filter can express them: a format's one
        can_id/can_mask becomes the channel's acceptance filter for that format, several go
        into its ID list. A set that does not fit the list (many wide 29-bit patterns) leaves
        both formats open and python-can matches every filter in software (`_recv_internal`
        says which). What an earlier call set is gone afterwards."""
        if self._channel is None:
            self._hw_filtered = True
            return
        self._hw_filtered = False  # until the channel holds the new filters
        with _vci_errors(self._initializing):
            _call("canChannelActivate", self._channel, 0)
            try:
                fits = [self._set_channel_filter(filters, extended) for extended in (False, True)]
                if not all(fits):
                    for extended in (0, 1):
                        _call("canChannelRemFilterIds", self._channel, extended, 0, 0)
                        _call("canChannelSetFilterMode", self._channel, extended,
                              _vci.CAN_FILTER_PASS, None)
            finally:
                _call("canChannelActivate", self._channel, 1)
        self._hw_filtered = all(fits)

    def _set_channel_filter(self, filters, extended: bool) -> bool:
        """Sets the channel's filter of one format (the channel is inactive); False when the
        filters do not fit its ID list. VciError when a call fails."""
        h = self._channel
        ext = int(extended)
        # The ID list empties first (code 0, mask 0 selects every value): the IDs an earlier
        # call listed must not pass any more.
        _call("canChannelRemFilterIds", h, ext, 0, 0)
        if not filters:
            _call("canChannelSetFilterMode", h, ext, _vci.CAN_FILTER_PASS, None)
            return True
        width = 0x1FFFFFFF if extended else 0x7FF
        patterns = []
        for f in filters:
            if f.get("extended", extended) != extended:
                continue
            can_id, can_mask = f["can_id"], f["can_mask"]
            if can_id & can_mask & ~width:
                continue  # wants identifier bits this format does not have: none of its frames
            # Filter values are (ID << 1) | RTR; RTR is left free (python-can ignores it).
            patterns.append(((can_id & can_mask & width) << 1, (can_mask & width) << 1))
        if not patterns:
            _call("canChannelSetFilterMode", h, ext, _vci.CAN_FILTER_LOCK, None)
            return True
        _call("canChannelSetFilterMode", h, ext, _vci.CAN_FILTER_INCL, None)
        if len(patterns) == 1:
            _call("canChannelSetAccFilter", h, ext, patterns[0][0], patterns[0][1])
            return True
        _call("canChannelSetAccFilter", h, ext, 0x80000000, 0xFFFFFFFF)  # accept none
        for code, mask in patterns:
            hr = _vci.lib().canChannelAddFilterIds(h, ext, code, mask)
            if hr == _vci.VCI_E_OUTOFMEMORY:
                return False  # does not fit the list: software
            _vci.check("canChannelAddFilterIds", hr)
        return True
