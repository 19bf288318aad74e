// ICanSocket: the properties and the state of a CAN connection, open to any number of programs
// (section 4.2.2). It holds no object in canemud: what it reports it reads through an object of
// the port this socket opened itself (the channel, control unit or cyclic list that derive from
// it), else through one opened for the moment and closed at once (docs/dotnet.md).
using System;
using Ixxat.Vci3.Bal;

namespace Ixxat.Vci3.Bal.Can
{
  public interface ICanSocket : IBalResource
  {
    CanCtrlType ControllerType { get; }
    CanBusCoupling BusCoupling { get; }
    bool SupportsStdOrExtFrames { get; }
    bool SupportsStdAndExtFrames { get; }
    bool SupportsRemoteFrames { get; }
    bool SupportsErrorFrames { get; }
    bool SupportsBusLoadComputation { get; }
    bool SupportsExactMessageFilter { get; }
    bool SupportsListenOnlyMode { get; }
    bool SupportsCyclicMessageScheduler { get; }
    bool SupportsErrorFrameGeneration { get; }
    bool SupportsDelayedTransmission { get; }
    bool SupportsSingleShotMessages { get; }
    bool SupportsHighPriorityMessages { get; }
    bool SupportsAutoBaudrateDetection { get; }
    // Clock of the time stamp, cyclic and delayed-transmission counters (Hz).
    uint ClockFrequency { get; }
    uint TimeStampCounterDivisor { get; }
    uint CyclicMessageTimeDivisor { get; }
    uint MaxCyclicMsgTicks { get; }
    uint DelayedTXTimerDivisor { get; }
    uint MaxDelayedTXTicks { get; }
    CanLineStatus LineStatus { get; }
  }

  internal class CanSocket : BalSocket, ICanSocket
  {
    internal CanSocket(BalObject bal, byte port) : base(bal, port) { }

    public override VciBusType BusType { get { return VciBusType.Can; } }
    protected override string Kind { get { return "ICanSocket"; } }

    // The capabilities / line status through this socket's own object, when it has one.
    protected virtual bool OwnCaps(byte[] caps) { return false; }
    protected virtual bool OwnLineStatus(byte[] status) { return false; }

    delegate uint Query(IntPtr h, byte[] buffer);

    // Asks through a control unit, else a channel, else a cyclic list opened for the moment
    // (each query writes its answer from offset 0: capabilities, or a status that starts with
    // the line status).
    byte[] Borrowed(string what, Query control, Query channel, Query scheduler)
    {
      var buffer = new byte[128];
      IntPtr h;
      uint hr = Native.canControlOpen(device, port, out h);
      if (hr == Native.VCI_OK)
      {
        try { Native.Check(control(h, buffer), what); } finally { Native.canControlClose(h); }
        return buffer;
      }
      if (hr != Native.E_ACCESSDENIED) Native.Check(hr, what);
      if (Native.canChannelOpen(device, port, 0, out h) == Native.VCI_OK)
      {
        try { Native.Check(channel(h, buffer), what); } finally { Native.canChannelClose(h); }
        return buffer;
      }
      if (Native.canSchedulerOpen(device, port, out h) == Native.VCI_OK)
      {
        try { Native.Check(scheduler(h, buffer), what); } finally { Native.canSchedulerClose(h); }
        return buffer;
      }
      throw new VciException(Native.E_ACCESSDENIED, what + ": other programs hold every object of CAN port " +
                             port + " (control unit, an exclusive channel, cyclic list); ask through one of them");
    }

    byte[] Caps()
    {
      Alive();
      var caps = new byte[128];
      if (OwnCaps(caps)) return caps;
      return Borrowed("ICanSocket capabilities", Native.canControlGetCaps, Native.canChannelGetCaps,
                      Native.canSchedulerGetCaps);
    }

    internal static CanLineStatus ParseLine(byte[] b, int at)
    {
      var s = new CanLineStatus();
      s.mode = (CanOperatingModes)b[at];
      s.busLoad = b[at + 2];
      s.bitrate = CanBitrate.FromBtp(b, at + 4);
      s.status = Bytes.U32(b, at + 36);
      return s;
    }

    public CanLineStatus LineStatus
    {
      get
      {
        Alive();
        var own = new byte[128];
        if (OwnLineStatus(own)) return ParseLine(own, 0);
        return ParseLine(Borrowed("ICanSocket.LineStatus", Native.canControlGetStatus,
                                  Native.canChannelGetStatus, Native.canSchedulerGetStatus), 0);
      }
    }

    uint Features { get { return Bytes.U32(Caps(), 4); } }
    bool Has(uint bit) { return (Features & bit) != 0; }

    public CanCtrlType ControllerType { get { return (CanCtrlType)Bytes.U16(Caps(), 0); } }
    public CanBusCoupling BusCoupling { get { return (CanBusCoupling)Bytes.U16(Caps(), 2); } }
    public bool SupportsStdOrExtFrames { get { return Has(0x0001); } }
    public bool SupportsStdAndExtFrames { get { return Has(0x0002); } }
    public bool SupportsRemoteFrames { get { return Has(0x0004); } }
    public bool SupportsErrorFrames { get { return Has(0x0008); } }
    public bool SupportsBusLoadComputation { get { return Has(0x0010); } }
    public bool SupportsExactMessageFilter { get { return Has(0x0020); } }
    public bool SupportsListenOnlyMode { get { return Has(0x0040); } }
    public bool SupportsCyclicMessageScheduler { get { return Has(0x0080); } }
    public bool SupportsErrorFrameGeneration { get { return Has(0x0100); } }
    public bool SupportsDelayedTransmission { get { return Has(0x0200); } }
    public bool SupportsSingleShotMessages { get { return Has(0x0400); } }
    public bool SupportsHighPriorityMessages { get { return Has(0x0800); } }
    public bool SupportsAutoBaudrateDetection { get { return Has(0x1000); } }
    public uint ClockFrequency { get { return Bytes.U32(Caps(), 76); } }
    public uint TimeStampCounterDivisor { get { return Bytes.U32(Caps(), 80); } }
    public uint CyclicMessageTimeDivisor { get { return Bytes.U32(Caps(), 88); } }
    public uint MaxCyclicMsgTicks { get { return Bytes.U32(Caps(), 92); } }
    public uint DelayedTXTimerDivisor { get { return Bytes.U32(Caps(), 100); } }
    public uint MaxDelayedTXTicks { get { return Bytes.U32(Caps(), 104); } }
  }
}
