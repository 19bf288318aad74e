// The LIN connection (section 4.3): ILinSocket, ILinMonitor with its reader, ILinControl.
using System;
using System.Threading;

namespace Ixxat.Vci3.Bal.Lin
{
  public interface ILinSocket : IBalResource
  {
    bool SupportsMasterMode { get; }
    bool SupportsAutorate { get; }
    bool SupportsErrorFrames { get; }
    bool SupportsBusLoadComputation { get; }
    bool SupportsSleepMessage { get; }
    bool SupportsWakeupMessage { get; }
    uint ClockFrequency { get; }
    uint TimeStampCounterDivisor { get; }
    LinLineStatus LineStatus { get; }
  }

  public interface ILinMessageReader : IDisposable
  {
    ushort Capacity { get; }
    ushort Threshold { get; set; }
    void AssignEvent(AutoResetEvent e);
    void AssignEvent(ManualResetEvent e);
    void AssignEvent(WaitHandle e);
    bool ReadMessage(out LinMessage message);
    int ReadMessages(LinMessage[] messages);
    bool GetMessage(out LinMessage message);
    int GetMessages(LinMessage[] messages);
  }

  public interface ILinMonitor : ILinSocket
  {
    void Initialize(ushort receiveFifoSize, bool exclusive);
    void Activate();
    void Deactivate();
    ILinMessageReader GetMessageReader();
  }

  public interface ILinControl : ILinSocket
  {
    void InitLine(LinInitLine initLine);
    void StartLine();
    void StopLine();
    void ResetLine();
    // send false: an entry of the response table; true: into the transmit buffer, at once.
    void WriteMessage(bool send, LinMessage message);
  }

  internal class LinSocket : BalSocket, ILinSocket
  {
    internal LinSocket(BalObject bal, byte port) : base(bal, port) { }
    public override VciBusType BusType { get { return VciBusType.Lin; } }
    protected override string Kind { get { return "ILinSocket"; } }
    protected virtual bool OwnCaps(byte[] caps) { return false; }
    protected virtual bool OwnStatus(byte[] status) { return false; }

    delegate uint Query(IntPtr h, byte[] b);

    byte[] Borrowed(string what, Query control, Query monitor)
    {
      var b = new byte[32];
      IntPtr h;
      uint hr = Native.linControlOpen(device, port, out h);
      if (hr == Native.VCI_OK)
      {
        try { Native.Check(control(h, b), what); } finally { Native.linControlClose(h); }
        return b;
      }
      if (hr != Native.E_ACCESSDENIED) Native.Check(hr, what);
      if (Native.linMonitorOpen(device, port, 0, out h) == Native.VCI_OK)
      {
        try { Native.Check(monitor(h, b), what); } finally { Native.linMonitorClose(h); }
        return b;
      }
      throw new VciException(Native.E_ACCESSDENIED, what + ": other programs hold the control unit and an exclusive monitor of LIN port " + port);
    }

    byte[] Caps()
    {
      Alive();
      var b = new byte[32];
      if (OwnCaps(b)) return b;
      return Borrowed("ILinSocket capabilities", Native.linControlGetCaps, Native.linMonitorGetCaps);
    }

    bool Has(uint bit) { return (Bytes.U32(Caps(), 0) & bit) != 0; }
    public bool SupportsMasterMode { get { return Has(0x01); } }
    public bool SupportsAutorate { get { return Has(0x02); } }
    public bool SupportsErrorFrames { get { return Has(0x04); } }
    public bool SupportsBusLoadComputation { get { return Has(0x08); } }
    public bool SupportsSleepMessage { get { return Has(0x10); } }
    public bool SupportsWakeupMessage { get { return Has(0x20); } }
    public uint ClockFrequency { get { return Bytes.U32(Caps(), 4); } }
    public uint TimeStampCounterDivisor { get { return Bytes.U32(Caps(), 8); } }

    public LinLineStatus LineStatus
    {
      get
      {
        Alive();
        var b = new byte[32];
        if (!OwnStatus(b)) b = Borrowed("ILinSocket.LineStatus", Native.linControlGetStatus, Native.linMonitorGetStatus);
        var s = new LinLineStatus();
        s.mode = (LinOperatingModes)b[0];
        s.bitrate = Bytes.U16(b, 2);
        s.status = Bytes.U32(b, 4);
        return s;
      }
    }
  }

  internal sealed class LinMonitor : LinSocket, ILinMonitor
  {
    IntPtr handle;
    ushort size, threshold = 1;
    bool initialized, active;
    Reader reader;

    internal LinMonitor(BalObject bal, byte port) : base(bal, port)
    {
      Native.Check(Native.linMonitorOpen(device, port, 0, out handle), "IBalObject.OpenSocket(" + port + ", ILinMonitor)");
    }

    protected override string Kind { get { return "ILinMonitor"; } }
    protected override bool OwnCaps(byte[] b) { return Native.linMonitorGetCaps(handle, b) == Native.VCI_OK; }
    protected override bool OwnStatus(byte[] b) { return Native.linMonitorGetStatus(handle, b) == Native.VCI_OK; }
    IntPtr H { get { Alive(); return handle; } }

    public void Initialize(ushort receiveFifoSize, bool exclusive)
    {
      var h = H;
      if (active) throw new VciException(Native.E_INVALID_STATE, "ILinMonitor.Initialize: the monitor is active; Deactivate it first");
      if (receiveFifoSize == 0) throw new VciException(Native.E_INVALIDARG, "ILinMonitor.Initialize: the FIFO size is counted in messages and must be at least 1");
      if (exclusive)
      {
        Native.linMonitorClose(handle);
        handle = IntPtr.Zero;
        IntPtr x;
        uint hr = Native.linMonitorOpen(device, port, 1, out x);
        if (hr != Native.VCI_OK)
        {
          Native.linMonitorOpen(device, port, 0, out handle);
          initialized = false;
          throw new VciException(hr, "ILinMonitor.Initialize(exclusive: true): another monitor of LIN port " + port +
                                     " is open; an exclusive monitor must be the only one: " + Native.Text(hr));
        }
        handle = x;
      }
      size = receiveFifoSize;
      Native.Check(Native.linMonitorInitialize(handle, size, Math.Min(threshold, size)), "ILinMonitor.Initialize");
      initialized = true;
    }

    void NeedInit(string what)
    {
      Alive();
      if (!initialized) throw new VciException(Native.E_INVALID_STATE, what + ": the monitor has no FIFO yet; call ILinMonitor.Initialize first");
    }

    public void Activate() { NeedInit("ILinMonitor.Activate"); Native.Check(Native.linMonitorActivate(handle, 1), "ILinMonitor.Activate"); active = true; }
    public void Deactivate() { NeedInit("ILinMonitor.Deactivate"); Native.Check(Native.linMonitorActivate(handle, 0), "ILinMonitor.Deactivate"); active = false; }

    public ILinMessageReader GetMessageReader()
    {
      NeedInit("ILinMonitor.GetMessageReader");
      if (reader != null) throw new VciException(Native.E_ACCESSDENIED, "ILinMonitor.GetMessageReader: the reader was obtained already; Dispose it before asking again");
      return reader = new Reader(this);
    }

    protected override void Release()
    {
      if (reader != null) reader.Dispose();
      if (handle != IntPtr.Zero) { Native.linMonitorClose(handle); handle = IntPtr.Zero; }
    }

    sealed class Reader : ILinMessageReader
    {
      readonly LinMonitor monitor;
      readonly FifoEvent ev;
      bool disposed;

      internal Reader(LinMonitor m)
      {
        monitor = m;
        ev = new FifoEvent(ms => Native.linMonitorWaitRxEvent(m.handle, ms));
      }

      IntPtr H { get { if (disposed) throw VciException.Disposed("ILinMessageReader"); return monitor.H; } }
      public ushort Capacity { get { var h = H; return monitor.size; } }
      public ushort Threshold
      {
        get { var h = H; return monitor.threshold; }
        set
        {
          var h = H;
          if (value == 0 || value > monitor.size) throw new VciException(Native.E_INVALIDARG, "ILinMessageReader.Threshold: " + value + " is not 1.." + monitor.size);
          if (monitor.active) throw new VciException(Native.E_INVALID_STATE, "ILinMessageReader.Threshold: the threshold can change only while the monitor is deactivated");
          monitor.threshold = value;
          Native.Check(Native.linMonitorInitialize(h, monitor.size, value), "ILinMessageReader.Threshold");
        }
      }
      public void AssignEvent(AutoResetEvent e) { AssignEvent((WaitHandle)e); }
      public void AssignEvent(ManualResetEvent e) { AssignEvent((WaitHandle)e); }
      public void AssignEvent(WaitHandle e) { var h = H; ev.Assign(FifoEvent.Check(e, "ILinMessageReader")); }

      public bool ReadMessage(out LinMessage message)
      {
        var b = new byte[Native.LinMsgSize];
        uint hr = Native.linMonitorPeekMessage(H, b);
        message = new LinMessage();
        if (hr == Native.E_RXQUEUE_EMPTY) return false;
        Native.Check(hr, "ILinMessageReader.ReadMessage");
        message = LinMessage.FromNative(b);
        ev.Touched();
        return true;
      }

      public int ReadMessages(LinMessage[] messages)
      {
        if (messages == null) throw new VciException(Native.E_INVALIDARG, "ILinMessageReader.ReadMessages: the array is null");
        int n = 0;
        LinMessage m;
        while (n < messages.Length && ReadMessage(out m)) messages[n++] = m;
        return n;
      }

      public bool GetMessage(out LinMessage message) { return ReadMessage(out message); }
      public int GetMessages(LinMessage[] messages) { return ReadMessages(messages); }

      public void Dispose()
      {
        if (disposed) return;
        disposed = true;
        ev.Dispose();
        monitor.reader = null;
      }
    }
  }

  internal sealed class LinControl : LinSocket, ILinControl
  {
    IntPtr handle;

    internal LinControl(BalObject bal, byte port) : base(bal, port)
    {
      uint hr = Native.linControlOpen(device, port, out handle);
      if (hr == Native.E_ACCESSDENIED)
        throw new VciException(hr, "IBalObject.OpenSocket(" + port + ", ILinControl): the control unit of LIN port " + port +
                                   " of " + bal.Name + " is in use by another program (one at a time)");
      Native.Check(hr, "IBalObject.OpenSocket(" + port + ", ILinControl)");
    }

    protected override string Kind { get { return "ILinControl"; } }
    protected override bool OwnCaps(byte[] b) { return Native.linControlGetCaps(handle, b) == Native.VCI_OK; }
    protected override bool OwnStatus(byte[] b) { return Native.linControlGetStatus(handle, b) == Native.VCI_OK; }
    IntPtr H { get { Alive(); return handle; } }

    public void InitLine(LinInitLine initLine)
    {
      var h = H;
      var rate = (ushort)initLine.Bitrate;
      if (rate != 0 && (rate < 1000 || rate > 20000))
        throw new VciException(Native.E_INVALIDARG, "ILinControl.InitLine: bit rate " + rate +
                               " bit/s is not 1000..20000 (LinBitrate.MinBitrate..MaxBitrate) or LinBitrate.AutoRate");
      uint hr = Native.linControlInitialize(h, (byte)initLine.OperatingMode, rate);
      if (hr != Native.VCI_OK)
        throw new VciException(hr, string.Format("ILinControl.InitLine({0}, {1} bit/s): {2}", initLine.OperatingMode, rate, Native.Text(hr)));
    }

    public void StartLine()
    {
      uint hr = Native.linControlStart(H, 1);
      if (hr == Native.E_INVALID_STATE) throw new VciException(hr, "ILinControl.StartLine: the line is not initialized; call InitLine first");
      Native.Check(hr, "ILinControl.StartLine");
    }

    public void StopLine() { Native.Check(Native.linControlStart(H, 0), "ILinControl.StopLine"); }
    public void ResetLine() { Native.Check(Native.linControlReset(H), "ILinControl.ResetLine"); }

    public void WriteMessage(bool send, LinMessage message)
    {
      var h = H;
      uint hr = Native.linControlWriteMessage(h, send ? 1 : 0, message.ToNative());
      if (hr == Native.VCI_OK) return;
      string why;
      if (hr == Native.E_TXQUEUE_FULL) why = "the transmit buffer is busy with the previous message (it holds one; try again when it went out)";
      else if (hr == Native.E_INVALID_STATE) why = "the line is not online (StartLine first)";
      else if (!send && (message.MessageType != LinMessageType.Data || message.ProtId > 63))
        why = "a response table entry must be LinMessageType.Data with an ID 0..63";
      else why = Native.Text(hr);
      throw new VciException(hr, string.Format("ILinControl.WriteMessage({0}, {1}): {2}", send, message, why));
    }

    protected override void Release()
    {
      if (handle != IntPtr.Zero) { Native.linControlClose(handle); handle = IntPtr.Zero; }
    }
  }
}
