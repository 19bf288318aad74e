// ICanControl: the control unit of a CAN connection (section 4.2.4), one program at a time:
// line state, bit rate and the two-stage message filter.
using System;

namespace Ixxat.Vci3.Bal.Can
{
  public interface ICanControl : ICanSocket
  {
    void InitLine(CanOperatingModes operatingMode, CanBitrate bitrate);
    // Tries the table's rates on the bus (timeout in ms per entry); the index found, or -1.
    int DetectBaud(ushort timeout, CanBitrate[] bitrateTable);
    void StartLine();
    void StopLine();
    void ResetLine();
    void SetAccFilter(CanFilter select, uint code, uint mask);
    void SetAccFilter(CanFilter select, CanAccCode code, CanAccMask mask);
    void AddFilterIds(CanFilter select, uint code, uint mask);
    void RemFilterIds(CanFilter select, uint code, uint mask);
  }

  internal sealed class CanControl : CanSocket, ICanControl
  {
    IntPtr handle;
    CanOperatingModes lastMode;
    CanBitrate lastBitrate;
    bool initialized;

    internal CanControl(BalObject bal, byte port) : base(bal, port)
    {
      uint hr = Native.canControlOpen(device, port, out handle);
      if (hr == Native.E_ACCESSDENIED)
        throw new VciException(hr, "IBalObject.OpenSocket(" + port + ", ICanControl): the control unit of CAN port " +
                                   port + " of " + bal.Name + " is in use by another program (one at a time)");
      Native.Check(hr, "IBalObject.OpenSocket(" + port + ", ICanControl)");
    }

    protected override string Kind { get { return "ICanControl"; } }
    protected override bool OwnCaps(byte[] caps) { return Native.canControlGetCaps(handle, caps) == Native.VCI_OK; }
    protected override bool OwnLineStatus(byte[] s) { return Native.canControlGetStatus(handle, s) == Native.VCI_OK; }

    IntPtr H { get { Alive(); return handle; } }

    void Init(CanOperatingModes mode, CanBitrate bitrate, string what)
    {
      var h = H;
      if (bitrate.Btr0 == 0 && bitrate.Btr1 == 0)
        throw new VciException(Native.E_INVALIDARG, what + ": the bit rate is empty (BTR0 = BTR1 = 0); use a CanBitrate preset or new CanBitrate(btr0, btr1)");
      // Both ID lists with room for every 11-bit key (4096) and as many 29-bit ones.
      uint hr = Native.canControlInitialize(h, (byte)mode, 0, 0x03 /* CAN_FILTER_INCL */, 0x03, 4096, 4096,
                                            bitrate.ToBtp(), null);
      if (hr != Native.VCI_OK)
        throw new VciException(hr, string.Format("{0}({1}, {2}): {3}", what, mode, bitrate, Native.Text(hr)));
      lastMode = mode;
      lastBitrate = bitrate;
      initialized = true;
    }

    public void InitLine(CanOperatingModes operatingMode, CanBitrate bitrate)
    {
      Init(operatingMode, bitrate, "ICanControl.InitLine");
    }

    public int DetectBaud(ushort timeout, CanBitrate[] bitrateTable)
    {
      var h = H;
      if (bitrateTable == null || bitrateTable.Length == 0 || bitrateTable.Length > 64)
        throw new VciException(Native.E_INVALIDARG, "ICanControl.DetectBaud: the table must hold 1..64 bit rates");
      var sdr = new byte[Native.BtpSize * bitrateTable.Length];
      var fdr = new byte[Native.BtpSize * bitrateTable.Length];
      for (int i = 0; i < bitrateTable.Length; i++)
        Buffer.BlockCopy(bitrateTable[i].ToBtp(), 0, sdr, i * Native.BtpSize, Native.BtpSize);
      uint index;
      initialized = false;  // afterwards the line is initialized with what was found, or not at all
      uint hr = Native.canControlDetectBitrate(h, 0x03, 0, timeout, (uint)bitrateTable.Length, sdr, fdr, out index);
      if (hr == Native.E_TIMEOUT) return -1;
      Native.Check(hr, "ICanControl.DetectBaud");
      if (index >= bitrateTable.Length) return -1;
      // The manual: after DetectBaud the line is offline, ready for StartLine (docs/dotnet.md).
      Init(CanOperatingModes.Standard | CanOperatingModes.Extended, bitrateTable[index], "ICanControl.DetectBaud");
      return (int)index;
    }

    public void StartLine()
    {
      uint hr = Native.canControlStart(H, 1);
      if (hr == Native.E_INVALID_STATE)
        throw new VciException(hr, "ICanControl.StartLine: the line is not initialized; call InitLine (or DetectBaud) first");
      Native.Check(hr, "ICanControl.StartLine");
    }

    public void StopLine() { Native.Check(Native.canControlStart(H, 0), "ICanControl.StopLine"); }
    // Resets the controller (a frame on the wire is aborted), clears the filters and leaves the
    // line offline with the modes and bit rate of the last InitLine, ready for StartLine
    // (section 4.2.4.1; docs/dotnet.md).
    public void ResetLine()
    {
      Native.Check(Native.canControlReset(H), "ICanControl.ResetLine");
      if (initialized) Init(lastMode, lastBitrate, "ICanControl.ResetLine");
    }

    delegate uint FilterCall(IntPtr h, int ext, uint code, uint mask);

    void Filter(FilterCall call, string what, CanFilter select, uint code, uint mask)
    {
      var h = H;
      if (select != CanFilter.Std && select != CanFilter.Ext)
        throw new VciException(Native.E_INVALIDARG, what + ": select must be CanFilter.Std or CanFilter.Ext, not " + (int)select);
      uint hr = call(h, select == CanFilter.Ext ? 1 : 0, code, mask);
      if (hr == Native.E_INVALID_STATE)
        throw new VciException(hr, what + ": the filters can change only while the line is offline (StopLine first)");
      if (hr != Native.VCI_OK)
        throw new VciException(hr, string.Format("{0}({1}, 0x{2:X}, 0x{3:X}): {4}", what, select, code, mask, Native.Text(hr)));
    }

    public void SetAccFilter(CanFilter select, uint code, uint mask)
    {
      Filter(Native.canControlSetAccFilter, "ICanControl.SetAccFilter", select, code, mask);
    }

    public void SetAccFilter(CanFilter select, CanAccCode code, CanAccMask mask)
    {
      SetAccFilter(select, (uint)code, (uint)mask);
    }

    public void AddFilterIds(CanFilter select, uint code, uint mask)
    {
      Filter(Native.canControlAddFilterIds, "ICanControl.AddFilterIds", select, code, mask);
    }

    public void RemFilterIds(CanFilter select, uint code, uint mask)
    {
      Filter(Native.canControlRemFilterIds, "ICanControl.RemFilterIds", select, code, mask);
    }

    protected override void Release()
    {
      if (handle != IntPtr.Zero) { Native.canControlClose(handle); handle = IntPtr.Zero; }
    }
  }
}
