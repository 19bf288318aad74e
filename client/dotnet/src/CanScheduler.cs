// ICanScheduler, the cyclic transmit list (section 4.2.5), and its CanCyclicTXMsg objects.
using System;
using System.Collections.Generic;

namespace Ixxat.Vci3.Bal.Can
{
  public class CanCyclicTXMsg
  {
    CanMessage message = new CanMessage();
    internal CanScheduler owner;
    internal uint index;
    CanCyclicTXStatus status = CanCyclicTXStatus.Empty;

    public ushort CycleTicks { get; set; }
    public CanCyclicTXIncMode AutoIncrementMode { get; set; }
    public byte AutoIncrementIndex { get; set; }
    // As the last ICanScheduler.UpdateStatus found it.
    public CanCyclicTXStatus Status { get { return status; } internal set { status = value; } }

    public uint Identifier { get { return message.Identifier; } set { message.Identifier = value; } }
    public byte DataLength { get { return message.DataLength; } set { message.DataLength = value; } }
    public bool RemoteTransmissionRequest { get { return message.RemoteTransmissionRequest; } set { message.RemoteTransmissionRequest = value; } }
    public bool ExtendedFrameFormat { get { return message.ExtendedFrameFormat; } set { message.ExtendedFrameFormat = value; } }
    public bool SelfReceptionRequest { get { return message.SelfReceptionRequest; } set { message.SelfReceptionRequest = value; } }
    public CanMsgFrameType FrameType { get { return CanMsgFrameType.Data; } }
    public byte this[int i] { get { return message[i]; } set { message[i] = value; } }

    // Starts it on the list it was added to (repeatCount 0: until stopped).
    public void Start(ushort repeatCount) { Owner("CanCyclicTXMsg.Start").StartMessage(this, repeatCount); }
    public void Start() { Start(0); }
    public void Stop() { Owner("CanCyclicTXMsg.Stop").StopMessage(this); }

    CanScheduler Owner(string what)
    {
      if (owner == null) throw new VciException(Native.E_INVALID_STATE, what + ": the message is on no cyclic list; ICanScheduler.AddMessage it first");
      return owner;
    }

    internal byte[] ToNative()
    {
      var m = message.ToNative();
      var b = new byte[Native.CanCyclic2Size];
      Bytes.Put16(b, 0, CycleTicks);
      b[2] = (byte)AutoIncrementMode;
      b[3] = AutoIncrementIndex;
      Bytes.Put32(b, 4, message.Identifier);
      Buffer.BlockCopy(m, 12, b, 8, 4 + 64);  // info and data
      b[8] = 0;  // CAN_MSGTYPE_DATA
      return b;
    }
  }

  public interface ICanScheduler : ICanSocket
  {
    void AddMessage(CanCyclicTXMsg message);
    void RemMessage(CanCyclicTXMsg message);
    void StartMessage(CanCyclicTXMsg message);
    void StartMessage(CanCyclicTXMsg message, ushort repeatCount);
    void StopMessage(CanCyclicTXMsg message);
    // Reads the status of the list and of every message on it (CanCyclicTXMsg.Status).
    void UpdateStatus();
    // True while the transmit task runs, as the last UpdateStatus found it.
    bool IsRunning { get; }
    void Resume();
    void Suspend();
    void Reset();
  }

  internal sealed class CanScheduler : CanSocket, ICanScheduler
  {
    IntPtr handle;
    readonly List<CanCyclicTXMsg> messages = new List<CanCyclicTXMsg>();
    bool running;

    internal CanScheduler(BalObject bal, byte port) : base(bal, port)
    {
      var caps = new byte[128];
      IntPtr h;
      uint hr = Native.canSchedulerOpen(device, port, out h);
      if (hr == Native.E_NOTIMPL || hr == Native.Code(0x0C) /* VCI_E_NOT_SUPPORTED */)
        throw new NotImplementedException("ICanScheduler: CAN port " + port + " of " + bal.Name + " has no cyclic transmit list");
      if (hr == Native.E_ACCESSDENIED)
        throw new VciException(hr, "IBalObject.OpenSocket(" + port + ", ICanScheduler): the cyclic transmit list of CAN port " +
                                   port + " of " + bal.Name + " is in use by another program (one at a time)");
      Native.Check(hr, "IBalObject.OpenSocket(" + port + ", ICanScheduler)");
      handle = h;
      if (Native.canSchedulerGetCaps(h, caps) == Native.VCI_OK && (Bytes.U32(caps, 4) & 0x0080) == 0)
      {
        Native.canSchedulerClose(h);
        handle = IntPtr.Zero;
        throw new NotImplementedException("ICanScheduler: CAN port " + port + " of " + bal.Name + " has no cyclic transmit list");
      }
    }

    protected override string Kind { get { return "ICanScheduler"; } }
    protected override bool OwnCaps(byte[] caps) { return Native.canSchedulerGetCaps(handle, caps) == Native.VCI_OK; }
    protected override bool OwnLineStatus(byte[] s) { return Native.canSchedulerGetStatus(handle, s) == Native.VCI_OK; }

    IntPtr H { get { Alive(); return handle; } }

    uint Mine(CanCyclicTXMsg m, string what)
    {
      if (m == null) throw new VciException(Native.E_INVALIDARG, what + ": the message is null");
      if (m.owner != this) throw new VciException(Native.E_INVALIDARG, what + ": the message was not added to this list with AddMessage");
      return m.index;
    }

    public void AddMessage(CanCyclicTXMsg message)
    {
      var h = H;
      if (message == null) throw new VciException(Native.E_INVALIDARG, "ICanScheduler.AddMessage: the message is null");
      if (message.owner != null) throw new VciException(Native.E_INVALIDARG, "ICanScheduler.AddMessage: the message is on a list already; RemMessage it first");
      uint index;
      uint hr = Native.canSchedulerAddMessage(h, message.ToNative(), out index);
      if (hr == Native.Code(0x03))  // VCI_E_OUTOFMEMORY
        throw new VciException(hr, string.Format("ICanScheduler.AddMessage(cycle {0}): no room: the list holds 16 messages and one per tick (the sum of 1/CycleTicks of its messages may not exceed 1)", message.CycleTicks));
      if (hr != Native.VCI_OK)
        throw new VciException(hr, string.Format("ICanScheduler.AddMessage(cycle {0}, mode {1}, index {2}): {3}", message.CycleTicks,
                                                 message.AutoIncrementMode, message.AutoIncrementIndex, Native.Text(hr)));
      message.owner = this;
      message.index = index;
      messages.Add(message);
    }

    public void RemMessage(CanCyclicTXMsg message)
    {
      uint i = Mine(message, "ICanScheduler.RemMessage");
      Native.Check(Native.canSchedulerRemMessage(H, i), "ICanScheduler.RemMessage");
      message.owner = null;
      message.Status = CanCyclicTXStatus.Empty;
      messages.Remove(message);
    }

    public void StartMessage(CanCyclicTXMsg message) { StartMessage(message, 0); }
    public void StartMessage(CanCyclicTXMsg message, ushort repeatCount)
    {
      uint i = Mine(message, "ICanScheduler.StartMessage");
      Native.Check(Native.canSchedulerStartMessage(H, i, repeatCount), "ICanScheduler.StartMessage");
    }

    public void StopMessage(CanCyclicTXMsg message)
    {
      uint i = Mine(message, "ICanScheduler.StopMessage");
      Native.Check(Native.canSchedulerStopMessage(H, i), "ICanScheduler.StopMessage");
    }

    public void UpdateStatus()
    {
      var b = new byte[Native.CanSchedStatus2Size];
      Native.Check(Native.canSchedulerGetStatus(H, b), "ICanScheduler.UpdateStatus");
      running = b[40] == 1;
      foreach (var m in messages) m.Status = (CanCyclicTXStatus)b[41 + m.index];
    }

    public bool IsRunning { get { Alive(); return running; } }
    public void Resume() { Native.Check(Native.canSchedulerActivate(H, 1), "ICanScheduler.Resume"); }
    public void Suspend() { Native.Check(Native.canSchedulerActivate(H, 0), "ICanScheduler.Suspend"); }

    public void Reset()
    {
      Native.Check(Native.canSchedulerReset(H), "ICanScheduler.Reset");
      foreach (var m in messages) { m.owner = null; m.Status = CanCyclicTXStatus.Empty; }
      messages.Clear();
    }

    protected override void Release()
    {
      foreach (var m in messages) m.owner = null;
      messages.Clear();
      if (handle != IntPtr.Zero) { Native.canSchedulerClose(handle); handle = IntPtr.Zero; }
    }
  }
}
